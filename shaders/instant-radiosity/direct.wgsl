// Direct irradiance from the lights, each seen by a shadow ray through the scene's BVH
// (`instant_radiosity::near_field::direct_irradiance`): what the near field's hits and
// point-based GI's surfels receive.
// #import tiled-shading/lighting.wgsl
// #import tiled-shading/rays.wgsl

// The lights' binding in group 0 (a specialisation may move it).
const DIRECT_LIGHTS: u32 = 3u;
@group(0) @binding(DIRECT_LIGHTS) var<storage, read> lights: array<Light>;

// Irradiance at y (unit normal n) from the first `count` lights; a directional light's ray is
// `reach` long.
fn direct_irradiance(y: vec3<f32>, n: vec3<f32>, count: u32, reach: f32) -> vec3<f32> {
    let origin = y + n * ray_lift(y);
    var e = vec3<f32>(0.0);
    for (var i = 0u; i < count; i++) {
        let light = lights[i];
        let inc = light_incidence(light, y);
        let cos_y = dot(n, inc.xyz);
        if inc.w <= 0.0 || cos_y <= 0.0 {
            continue;
        }
        var to = light.position - origin;
        if light.kind == LIGHT_DIRECTIONAL {
            to = -light.direction * reach;
        }
        if !occluded(origin, to) {
            e += light.color * (inc.w * cos_y);
        }
    }
    return e;
}
