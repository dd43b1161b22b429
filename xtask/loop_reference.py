"""Independent Loop subdivision results for the subdiv-bft tests (run by `cargo xtask subdiv-fixtures`).

For each closed mesh of ../shared/fixtures listed below, applies MeshLab's Loop subdivision
(pymeshlab `meshing_surface_subdivision_loop(loopweight='Loop', threshold=0)`, which matches
OpenSubdiv's Hbr) 1 and 2 times and writes the refined vertex positions as little-endian f32
xyz triples to fixtures/subdiv/<name>_loop<N>.f32. trimesh's `remesh.subdivide_loop` (valid on
closed meshes) is run too and must agree to 1e-5 of the bounding-box diagonal, so the two
tools check each other before anything is written.
"""
import sys, os, struct

import numpy as np
import pymeshlab
import trimesh

MESHES = [("spot", "subdiv/spot/spot_triangulated.obj", [1, 2]), ("fandisk", "subdiv/fandisk.obj", [1])]


def read_obj(path):
    # Positions and faces only (trimesh's OBJ loader splits vertices at texture seams).
    v, f = [], []
    for line in open(path):
        w = line.split()
        if w and w[0] == "v":
            v.append([float(x) for x in w[1:4]])
        elif w and w[0] == "f":
            idx = [int(x.split("/")[0]) - 1 for x in w[1:]]
            f.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))
    return trimesh.Trimesh(vertices=np.array(v), faces=np.array(f), process=False)


def max_nearest(a, b):
    tree_a = trimesh.points.PointCloud(a).kdtree
    tree_b = trimesh.points.PointCloud(b).kdtree
    return max(tree_b.query(a)[0].max(), tree_a.query(b)[0].max())


def main(shared, out):
    for name, rel, levels in MESHES:
        src = os.path.join(shared, rel)
        base = read_obj(src)
        assert base.is_watertight, f"{name} is not closed"
        diag = np.linalg.norm(base.bounds[1] - base.bounds[0])
        for level in levels:
            ms = pymeshlab.MeshSet()
            ms.add_mesh(pymeshlab.Mesh(vertex_matrix=base.vertices, face_matrix=base.faces))
            for _ in range(level):
                ms.meshing_surface_subdivision_loop(loopweight="Loop", iterations=1, threshold=pymeshlab.PercentageValue(0))
            pm = ms.current_mesh().vertex_matrix()
            v, f = base.vertices, base.faces
            for _ in range(level):
                v, f = trimesh.remesh.subdivide_loop(v, f, iterations=1)
            assert len(pm) == len(v), f"{name} level {level}: meshlab {len(pm)} vs trimesh {len(v)} vertices"
            err = max_nearest(pm, v) / diag
            assert err < 1e-5, f"{name} level {level}: meshlab and trimesh differ by {err:e}"
            path = os.path.join(out, f"{name}_loop{level}.f32")
            with open(path, "wb") as fh:
                fh.write(struct.pack(f"<{pm.size}f", *pm.astype(np.float32).ravel()))
            print(f"{path}: {len(pm)} vertices (meshlab vs trimesh {err:.2e} of the diagonal)")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
