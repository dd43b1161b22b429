// The scene's meshes in triangle-id order, shared by the visibility buffer's rasteriser and its
// resolve (`gbuffer::gpu::visibility::MeshEntry`): binding 1 of group 0 in both.

struct Mesh {
    first_id: u32,
    base_vertex: u32,
    first_index: u32,
    // Triangles drawn (ids from first_id on); 0 for a mesh left out.
    triangle_count: u32,
    // 1 where the mesh's material is one-sided: back faces are culled.
    cull_back: u32,
    material: u32,
    // The resolve's index of the material (dense over the materials drawn); none for a mesh
    // left out.
    slot: u32,
    _pad: u32,
}

@group(0) @binding(1) var<storage, read> meshes: array<Mesh>;

// The mesh holding triangle `id`: the last entry whose first id is ≤ id.
fn mesh_of(id: u32) -> u32 {
    var lo = 0u;
    var hi = arrayLength(&meshes);
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if meshes[mid].first_id <= id {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}
