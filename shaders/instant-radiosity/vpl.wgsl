// A VPL as the shaders see it (`instant_radiosity::vpl::GpuVpl`) and the light it sends
// (`instant_radiosity::cpu::vpl_intensity`).

struct Vpl {
    position: vec3<f32>,
    _pad0: f32,
    normal: vec3<f32>,
    _pad1: f32,
    flux: vec3<f32>,
    _pad2: f32,
};

const INV_PI_VPL: f32 = 0.318309886183791;

// The intensity of `vpl` towards p, Φ/π · max(−n_q·l, 0) / max(d², clamp²): the clamp bounds
// the 1/d² singularity of VPLs close to the receiver. The direction to the VPL goes to `l`.
// One reciprocal square root serves both: 1 / max(d², clamp²) = min((1/d)², 1/clamp²).
fn vpl_intensity(vpl: Vpl, p: vec3<f32>, clamp_squared: f32, l: ptr<function, vec3<f32>>) -> vec3<f32> {
    let to_vpl = vpl.position - p;
    let inv_d = inverseSqrt(max(dot(to_vpl, to_vpl), 1e-30));
    let dir = to_vpl * inv_d;
    *l = dir;
    let cos_vpl = max(-dot(vpl.normal, dir), 0.0);
    return vpl.flux * (INV_PI_VPL * cos_vpl * min(inv_d * inv_d, 1.0 / clamp_squared));
}
