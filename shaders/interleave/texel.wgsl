// #import interleave/pattern.wgsl
// Texel type, bindings and pattern constants shared by the split and gather kernels
// (Segovia 2006 §3). Written for r32uint; `interleave::gpu::texel_specialisation` sets the
// three aliases `Texel`, `Source` and `Destination` for the format being split, so one kernel
// moves any supported format bit for bit.

alias Texel = vec4<u32>;
alias Source = texture_2d<u32>;
alias Destination = texture_storage_2d<r32uint, write>;
@group(0) @binding(0) var source: Source;
@group(0) @binding(1) var destination: Destination;

// Sub-block (two-pass) or tile run (tiled) of a × b sub-buffer texels.
override a: u32 = 1u;
override b: u32 = 1u;

fn load_pixel(x: u32, y: u32) -> Texel {
    var t = Texel();
    if x < width && y < height {
        t = textureLoad(source, vec2(x, y), 0);
    }
    return t;
}
