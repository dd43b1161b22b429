// The light accumulation's parameters (`tiled_shading::gpu::ShadingParams`), shared by the
// G-buffer passes (`pixels.wgsl`) and the Forward+ pass (`forward.wgsl`).

struct Params {
    light_count: u32,
    tiles_x: u32,
    // 1: write every tile's list to `lists` (tests, Forward+); 0: only the counts.
    record_lists: u32,
    // Entries per tile in `lists` (a longer list keeps its first `list_stride`).
    list_stride: u32,
    // Exponential cluster slicing (`Slicing`); `slice_near` is the camera's near plane.
    slice_near: f32,
    slice_scale: f32,
    // Groups of the light hierarchy (`LightGroups`).
    group_count: u32,
    _pad0: u32,
};
