// The output transform (issue 22): exposure, fixed (EV) or automatic from the frame's
// log-average luminance (Reinhard et al. 2002, key 0.18), then a tone mapper — the fitted
// ACES RRT + ODT (Hill 2016) or a plain clamp — into display-linear RGB in [0, 1]; the sRGB
// encode happens where the image is stored (an sRGB target or the PNG writer). Twin of
// `pipeline::output::OutputTransform::apply`.

struct OutputParams {
    // 2^EV.
    exposure: f32,
    // 1: multiply by key / log-average luminance.
    auto_exposure: u32,
    // 0: clamp, 1: ACES fitted.
    tone_mapper: u32,
    // Partial sums written by `log_luminance_main` (one per workgroup).
    partials: u32,
};

const KEY: f32 = 0.18;
const LOG_DELTA: f32 = 1e-4;

@group(0) @binding(0) var<uniform> params: OutputParams;
@group(0) @binding(1) var radiance_in: texture_2d<f32>;
// Per workgroup: (Σ log(δ + L), count of lit pixels); then, at index `partials`, the exposure.
@group(0) @binding(2) var<storage, read_write> sums: array<vec2<f32>>;
@group(0) @binding(3) var display_out: texture_storage_2d<rgba16float, write>;

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

var<workgroup> shared_sums: array<vec2<f32>, 256>;

// The workgroup's 256 values of `shared_sums`, after this invocation stored its own at `local`,
// summed into `shared_sums[0]` (a tree, halving the stride).
fn reduce_shared(local: u32) {
    workgroupBarrier();
    for (var stride = 128u; stride > 0u; stride = stride / 2u) {
        if local < stride {
            shared_sums[local] = shared_sums[local] + shared_sums[local + stride];
        }
        workgroupBarrier();
    }
}

// Σ log(δ + L) and the count of pixels with L > 0, per 16 × 16 tile.
@compute @workgroup_size(16, 16)
fn log_luminance_main(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let size = textureDimensions(radiance_in);
    var s = vec2<f32>(0.0);
    if id.x < size.x && id.y < size.y {
        let l = luminance(textureLoad(radiance_in, id.xy, 0).rgb);
        if l > 0.0 {
            s = vec2<f32>(log(LOG_DELTA + l), 1.0);
        }
    }
    shared_sums[local] = s;
    reduce_shared(local);
    if local == 0u {
        sums[group.y * groups.x + group.x] = shared_sums[0];
    }
}

// One workgroup: the partial sums' total, then the exposure.
@compute @workgroup_size(256)
fn exposure_main(@builtin(local_invocation_index) local: u32) {
    var s = vec2<f32>(0.0);
    for (var i = local; i < params.partials; i = i + 256u) {
        s = s + sums[i];
    }
    shared_sums[local] = s;
    reduce_shared(local);
    if local == 0u {
        let total = shared_sums[0];
        var exposure = params.exposure;
        if params.auto_exposure != 0u && total.y > 0.0 {
            exposure = exposure * KEY / exp(total.x / total.y);
        }
        sums[params.partials] = vec2<f32>(exposure, 0.0);
    }
}

// Hill's fit of the ACES reference rendering and output device transforms (sRGB, 100 nits).
fn aces_fitted(c: vec3<f32>) -> vec3<f32> {
    let input = mat3x3<f32>(
        vec3<f32>(0.59719, 0.07600, 0.02840),
        vec3<f32>(0.35458, 0.90834, 0.13383),
        vec3<f32>(0.04823, 0.01566, 0.83777),
    );
    let output = mat3x3<f32>(
        vec3<f32>(1.60475, -0.10208, -0.00327),
        vec3<f32>(-0.53108, 1.10813, -0.07276),
        vec3<f32>(-0.07367, -0.00605, 1.07602),
    );
    let v = input * c;
    let a = v * (v + 0.0245786) - 0.000090537;
    let b = v * (0.983729 * v + 0.4329510) + 0.238081;
    return output * (a / b);
}

@compute @workgroup_size(8, 8)
fn output_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(radiance_in);
    if id.x >= size.x || id.y >= size.y { return; }
    let c = textureLoad(radiance_in, id.xy, 0).rgb * sums[params.partials].x;
    var display = c;
    if params.tone_mapper == 1u {
        display = aces_fitted(c);
    }
    textureStore(display_out, id.xy, vec4<f32>(clamp(display, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0));
}
