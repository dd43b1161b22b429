// Progressive accumulation (Segovia 2006 §6.3): the running mean of the frames' radiance,
// mean_k = mean_{k−1} + (x_k − mean_{k−1}) / k, so frame k weighs as much as every other.
// Twin of `pipeline::progressive::accumulate`.

struct AccumulateParams {
    // Frames in the mean after this one (1: the mean is this frame).
    count: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
};

@group(0) @binding(0) var<uniform> params: AccumulateParams;
@group(0) @binding(1) var radiance: texture_2d<f32>;
@group(0) @binding(2) var<storage, read_write> mean: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn accumulate(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(radiance);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let i = id.y * size.x + id.x;
    let x = textureLoad(radiance, id.xy, 0);
    if params.count <= 1u {
        mean[i] = x;
    } else {
        mean[i] = mean[i] + (x - mean[i]) / f32(params.count);
    }
}
