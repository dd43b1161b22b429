// #import tiled-shading/shadows.wgsl
// #import tiled-shading/pixels.wgsl
// Traditional deferred shading with light volumes (Ishmukhametov 2013 §4.1, after Hargreaves
// 2004): every light is drawn as an instance of a low-polygon volume that encloses its
// influence — a sphere for point and hemispherical lights, a cone for narrow spots, a
// full-screen triangle for directional lights — back faces only (no stencil: correct with the
// eye inside a volume), depth-tested `GreaterEqual` against the scene so only pixels whose
// surface lies in front of the volume's back face are shaded; each fragment evaluates the one
// light at its G-buffer pixel, discards a zero contribution, and is added into the diffuse and
// specular accumulation targets by the blender. Same BRDF as `tiled.wgsl`'s `brute_force`, so
// the same image up to the order of the sums. `tiled_shading::gpu::volumes` builds the meshes
// and the draw order.

// Light indices in draw order: the sphere lights, the cone lights, the directional lights.
@group(0) @binding(7) var<storage, read> order: array<u32>;
// The unit volumes' triangle corners, outward faces counter-clockwise; w tags the mesh: a
// sphere of inner radius 1 (w 0), a cone with its apex at the origin along +z, height 1, whose
// base polygon holds the circle of radius 1 (w 1), a full-screen triangle in clip space (w 2).
@group(0) @binding(8) var<storage, read> corners: array<vec4<f32>>;

// Off for the pipeline without the depth test: every vertex then gets depth ½ (the same
// pixels, never clipped by the far plane, which would cut off the back faces beyond it).
override DEPTH_TESTED: bool = true;

const MESH_CONE: f32 = 1.0;
const MESH_SCREEN: f32 = 2.0;

struct Fragment {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) light: u32,
};

struct Accumulation {
    @location(0) diffuse: vec4<f32>,
    @location(1) specular: vec4<f32>,
};

// A unit vector perpendicular to unit `a` (Duff et al. 2017's branchless basis).
fn perpendicular(a: vec3<f32>) -> vec3<f32> {
    let s = select(-1.0, 1.0, a.z >= 0.0);
    let k = -1.0 / (s + a.z);
    return vec3<f32>(1.0 + s * a.x * a.x * k, s * a.x * a.y * k, -s * a.x);
}

@vertex
fn volume_vertex(@builtin(vertex_index) vertex: u32, @builtin(instance_index) instance: u32) -> Fragment {
    let index = order[instance];
    let light = lights[index];
    let c = corners[vertex];
    var out: Fragment;
    out.light = index;
    if c.w == MESH_SCREEN {
        // On the far plane: behind every surface.
        out.clip = vec4<f32>(c.xy, 1.0, 1.0);
        return out;
    }
    var p = light.position + light.radius * c.xyz;
    if c.w == MESH_CONE {
        // The cone of the outer angle, as long as the radius: it holds the spot's sector.
        let axis = light.direction;
        let t = perpendicular(axis);
        let b = cross(axis, t);
        let tan_outer = sqrt(max(1.0 - light.cos_outer * light.cos_outer, 0.0)) / light.cos_outer;
        p = light.position + light.radius * (c.z * axis + tan_outer * (c.x * t + c.y * b));
    }
    out.clip = frame.view_proj * vec4<f32>(p, 1.0);
    if !DEPTH_TESTED {
        out.clip.z = 0.5 * out.clip.w;
    }
    return out;
}

@fragment
fn volume_fragment(in: Fragment) -> Accumulation {
    let pixel = vec2<u32>(in.clip.xy);
    let s = load_sample(pixel, textureDimensions(linear_depth_texture));
    if !s.present {
        discard;
    }
    let m = load_material(pixel);
    let v = normalize(frame.eye.xyz - s.position);
    let c = shade_shadowed(lights[in.light], s.position, s.normal, v, m.albedo, m.roughness, m.metallic, m.specular);
    if all(c.diffuse == vec3<f32>(0.0)) && all(c.specular == vec3<f32>(0.0)) {
        discard;
    }
    return Accumulation(vec4<f32>(c.diffuse, 0.0), vec4<f32>(c.specular, 0.0));
}
