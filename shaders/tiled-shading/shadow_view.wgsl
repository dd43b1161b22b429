// One depth view of a light (`tiled_shading::shadows::ShadowView`): world → clip with depth 0
// at `near` and 1 at `far` along `axis`; `texel` is a texel's world size at unit distance
// (perspective) or everywhere (orthographic).
struct ShadowView {
    view_proj: mat4x4<f32>,
    axis: vec3<f32>,
    near: f32,
    far: f32,
    orthographic: u32,
    texel: f32,
    _pad: u32,
};

fn linear_shadow_depth(v: ShadowView, d: f32) -> f32 {
    if v.orthographic == 1u {
        return v.near + d * (v.far - v.near);
    }
    return v.near * v.far / (v.far - d * (v.far - v.near));
}

