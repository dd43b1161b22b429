// #import tiled-shading/shadow_view.wgsl
// Depth of the scene in the shadow views (`tiled_shading::gpu::shadows`): one render pass per
// view (a depth-array layer), drawn with the instance index = the view.

@group(0) @binding(0) var<storage, read> views: array<ShadowView>;

@vertex
fn shadow_depth(@location(0) position: vec3<f32>, @builtin(instance_index) view: u32) -> @builtin(position) vec4<f32> {
    return views[view].view_proj * vec4<f32>(position, 1.0);
}
