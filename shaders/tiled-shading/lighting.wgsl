// Lights and the BRDF of the deferred renderer; mirrors `pipeline::cpu` (same names).
//
// Light accumulation (Ishmukhametov 2013 §1.3 step 3) sums, per pixel and light,
//   E = Att · (N·L) · colour · intensity
//   diffuse  += E / π
//   specular += E · D_GGX(N·H) · V_SmithGGX(N·L, N·V) · F_Schlick(V·H, F0)
// with F = mix(specular · F_Schlick(0.04), F_Schlick(albedo), metallic) (specular: the
// material's factor, in the G-buffer albedo's alpha) and α = roughness². Composition (step 4):
//   colour = albedo · (1 − metallic) · (ambient + diffuse) + specular + emissive.
// Point, spot and hemispherical attenuation: saturate(1 − (d/r)⁴)² / max(d², 1e-4), exactly zero
// at r; spot lights fade by smoothstep(cos outer, cos inner, cos θ), hemispherical ones by max(cos θ, 0).

const LIGHT_POINT: u32 = 0u;
const LIGHT_SPOT: u32 = 1u;
const LIGHT_DIRECTIONAL: u32 = 2u;
const LIGHT_HEMISPHERICAL: u32 = 3u;
const INV_PI: f32 = 0.318309886183791;

struct Light {
    position: vec3<f32>,
    radius: f32,
    // colour × intensity
    color: vec3<f32>,
    kind: u32,
    // direction the light travels (spot, directional)
    direction: vec3<f32>,
    cos_outer: f32,
    cos_inner: f32,
    // the light's shadow views (shadows.wgsl); count 0: unshadowed
    shadow_first: u32,
    shadow_count: u32,
    _pad: u32,
};

// Distance window: 1 at the light, 0 at and beyond its radius.
fn distance_attenuation(d: f32, radius: f32) -> f32 {
    let x = d / radius;
    let x2 = x * x;
    let w = clamp(1.0 - x2 * x2, 0.0, 1.0);
    return w * w / max(d * d, 1e-4);
}

// Direction to the light and attenuation at `p` (zero outside the light's influence).
fn light_incidence(light: Light, p: vec3<f32>) -> vec4<f32> {
    if light.kind == LIGHT_DIRECTIONAL {
        return vec4<f32>(-light.direction, 1.0);
    }
    let to_light = light.position - p;
    let d = length(to_light);
    let l = to_light / max(d, 1e-6);
    var att = distance_attenuation(d, light.radius);
    let cos_emission = dot(-l, light.direction);
    if light.kind == LIGHT_SPOT {
        att *= smoothstep(light.cos_outer, light.cos_inner, cos_emission);
    } else if light.kind == LIGHT_HEMISPHERICAL {
        att *= max(cos_emission, 0.0);
    }
    return vec4<f32>(l, att);
}

struct Accumulated {
    diffuse: vec3<f32>,
    specular: vec3<f32>,
};

fn shade_light(light: Light, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, albedo: vec3<f32>, roughness: f32, metallic: f32, specular: f32) -> Accumulated {
    let inc = light_incidence(light, p);
    if inc.w <= 0.0 {
        var none: Accumulated;
        none.diffuse = vec3<f32>(0.0);
        none.specular = vec3<f32>(0.0);
        return none;
    }
    return reflect_light(light.color * inc.w, inc.xyz, n, v, albedo, roughness, metallic, specular);
}

// Light arriving along `l` with attenuated `intensity` (irradiance intensity · N·L), reflected
// towards `v`: Lambert E/π and GGX E·D·V·F.
fn reflect_light(intensity: vec3<f32>, l: vec3<f32>, n: vec3<f32>, v: vec3<f32>, albedo: vec3<f32>, roughness: f32, metallic: f32, specular: f32) -> Accumulated {
    var out: Accumulated;
    out.diffuse = vec3<f32>(0.0);
    out.specular = vec3<f32>(0.0);
    let n_dot_l = clamp(dot(n, l), 0.0, 1.0);
    if n_dot_l <= 0.0 {
        return out;
    }
    let e = intensity * n_dot_l;
    out.diffuse = e * INV_PI;
    // The half vector h = (l + v) / |l + v| enters through n·h and v·h = l·h only, which
    // follow from n·l, n·v and l·v without forming it.
    let l_dot_v = dot(l, v);
    let inv_h = inverseSqrt(max(2.0 + 2.0 * l_dot_v, 1e-12));
    let n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    let n_dot_h = clamp((n_dot_l + dot(n, v)) * inv_h, 0.0, 1.0);
    let v_dot_h = clamp((1.0 + l_dot_v) * inv_h, 0.0, 1.0);
    let a = max(roughness * roughness, 1e-3);
    let a2 = a * a;
    let k = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    // D · V = a²/π / k² · 1/2 / (n·l √(n·v² (1 − a²) + a²) + n·v √(n·l² (1 − a²) + a²)).
    let smith = n_dot_l * sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2) + n_dot_v * sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2);
    let d_vis = a2 * (0.5 * INV_PI) / (k * k * smith);
    let x = 1.0 - v_dot_h;
    let x2 = x * x;
    let fw = x2 * x2 * x;
    // Schlick from F0 = 0.04 (dielectric, scaled by the specular factor as in
    // KHR_materials_specular) or the albedo (metal).
    let f = mix(vec3<f32>(specular * (0.04 + 0.96 * fw)), albedo + (vec3<f32>(1.0) - albedo) * fw, metallic);
    out.specular = e * d_vis * f;
    return out;
}

// Rec. 709 luminance (`scene::luminance`).
fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}
