// #import tiled-shading/shadow_view.wgsl
// #import manylod/lookup.wgsl
// The reindexing of Segovia 2006 §4.3's SSM: every VPL's hemicube was rasterised into one
// depth atlas of faces ("unrolling the hemicube in a standard shadow map"); here each texel
// of the VPL's paraboloid tile takes the distance the hemicube saw along the direction of
// the texel's centre, from the face of that direction's largest axis, packed as the ManyLoD
// splats pack it, so the shading looks every mode up the same way
// (`instant_radiosity::ssm`; CPU twin `tiled_shading::shadows::ray_cast_atlas`).

struct SsmParams {
    // The batch's first VPL and its VPL count.
    first_view: u32,
    views: u32,
    // Hemicube face side in texels and faces per row of the face atlas.
    face: u32,
    face_columns: u32,
    // Paraboloid tile side, tiles per row and row length of the paraboloid atlas.
    tile: u32,
    columns: u32,
    width: u32,
    // Distance packed as depth 1.
    far: f32,
};

const HEMICUBE_FACES: u32 = 5u;
const EMPTY: u32 = 0xffffffffu;

@group(0) @binding(0) var<storage, read> views: array<ShadowView>;
@group(0) @binding(1) var faces: texture_depth_2d;
@group(0) @binding(2) var<uniform> params: SsmParams;
@group(0) @binding(3) var<storage, read_write> atlas: array<u32>;

// Invocation (x, y, v): texel (x, y) of the tile of the batch's VPL v.
@compute @workgroup_size(8, 8)
fn reindex(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.tile || id.y >= params.tile || id.z >= params.views {
        return;
    }
    let k = params.first_view + id.z;
    let corner = vec2<u32>(k % params.columns, k / params.columns) * params.tile;
    let index = (corner.y + id.y) * params.width + corner.x + id.x;
    // The inverse of uv = l.xy / (1 + l.z) on the unit sphere; outside the disc is no direction.
    let uv = (vec2<f32>(id.xy) + 0.5) / f32(params.tile) * 2.0 - 1.0;
    let r2 = dot(uv, uv);
    if r2 >= 1.0 {
        atlas[index] = EMPTY;
        return;
    }
    let z = (1.0 - r2) / (1.0 + r2);
    let frame = paraboloid_frame(views[k * HEMICUBE_FACES].axis);
    let dir = normalize(frame * vec3<f32>(uv * (1.0 + z), z));
    var best = 0u;
    var cos_best = -2.0;
    for (var f = 0u; f < HEMICUBE_FACES; f++) {
        let c = dot(dir, views[k * HEMICUBE_FACES + f].axis);
        if c > cos_best {
            cos_best = c;
            best = f;
        }
    }
    let view = views[k * HEMICUBE_FACES + best];
    // A direction (w = 0) projects like the point at unit distance from the view's origin.
    let clip = view.view_proj * vec4<f32>(dir, 0.0);
    let ndc = clip.xy / clip.w;
    let texel = min(
        vec2<u32>(vec2<f32>(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y) * f32(params.face)),
        vec2<u32>(params.face - 1u),
    );
    let slot = id.z * HEMICUBE_FACES + best;
    let face_corner = vec2<u32>(slot % params.face_columns, slot / params.face_columns) * params.face;
    let d = textureLoad(faces, face_corner + texel, 0);
    if d >= 1.0 {
        atlas[index] = EMPTY;
        return;
    }
    // Distance along the axis over the direction's cosine to the axis: distance along dir.
    atlas[index] = pack_depth(linear_shadow_depth(view, d) / clip.w / params.far, 0u);
}
