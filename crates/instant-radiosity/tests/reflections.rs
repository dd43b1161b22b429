//! Reflection maps through many-view cuts (Holländer 2013 §3.6.1, Fig. 3.19): the probes of a
//! scene, GPU maps == CPU maps, the maps against rays cast from the probes through the scene's
//! triangles (the ground truth), and the frame's reflection pass against its CPU twin.

use glam::Vec3;
use instant_radiosity::pbgi::{LitPoints, PbgiConfig};
use instant_radiosity::reflections::{
    GpuReflections, Probes, REFLECTION_FORMAT, has_probes, is_glass, map_texel, reflect,
};
use instant_radiosity::vpl;
use tiled_shading::GpuLight;

fn lamp(scene: &scene::Scene) -> Vec<GpuLight> {
    let (lights, _, _) = vpl::primary_lights_sampled(scene, 16);
    lights.iter().map(GpuLight::from).collect()
}

const TILE: u32 = 32;

#[test]
fn probes_sit_at_the_mirror_meshes() {
    let scene = scene::mirror_spheres(8);
    let probes = Probes::of_scene(&scene);
    assert_eq!(probes.len(), 8, "one probe per sphere");
    let probed: Vec<usize> = (0..scene.materials.len())
        .filter(|&m| has_probes(&scene.materials[m]))
        .collect();
    assert_eq!(probed.len(), 4, "two metals, two glasses");
    for (m, row) in probes.materials.iter().enumerate() {
        assert_eq!(row.count, if probed.contains(&m) { 2 } else { 0 });
        let material = &scene.materials[m];
        assert_eq!(
            row.transmission > 0.0,
            is_glass(material),
            "{}",
            material.name
        );
    }
    assert_eq!(
        probes
            .materials
            .iter()
            .filter(|r| r.transmission > 0.0)
            .count(),
        2,
        "clear and green glass"
    );
    // A point on a sphere's surface reflects from that sphere's probe.
    for mesh in scene.meshes.iter().filter(|m| m.name.starts_with("sphere")) {
        let p = mesh.positions[7];
        let probe = probes.nearest(mesh.material, p).expect("a probe");
        let center = probes.centers[probe];
        let radius = mesh
            .positions
            .iter()
            .map(|q| q.distance(center))
            .fold(0.0, f32::max);
        assert!((p.distance(center) - radius).abs() < 1e-3 * radius.max(1.0));
    }
    assert_eq!(
        probes.nearest(0, Vec3::ZERO),
        None,
        "the walls reflect nothing"
    );
}

/// Glass in closed form: under a uniform environment of radiance `L`, clear glass that
/// transmits all returns `F · L + (1 − F) · L = L` at every angle (nothing is absorbed); seen
/// head-on it reflects `F0 = ((ior − 1)/(ior + 1))² = 0.04` of what lies in front (the map's
/// +Y half, seen from above) and transmits `0.96 · tint` of what lies behind (−Y, the ray
/// passes straight through); a mirror transmits nothing.
#[test]
fn glass_reflects_and_transmits_by_fresnel() {
    let scene = scene::mirror_spheres(4);
    let probes = Probes::of_scene(&scene);
    let clear = scene
        .materials
        .iter()
        .position(|m| m.name == "glass")
        .expect("glass") as u32;
    let green = scene
        .materials
        .iter()
        .position(|m| m.name == "green glass")
        .expect("tint") as u32;
    let silver = scene
        .materials
        .iter()
        .position(|m| m.name == "silver")
        .expect("silver") as u32;
    let center = probes.centers[probes.nearest(clear, Vec3::ZERO).expect("a probe")];
    let texels = (TILE * TILE) as usize;
    let (above, below) = (Vec3::new(0.2, 0.5, 0.9), Vec3::new(0.7, 0.3, 0.1));
    let maps: Vec<Vec3> = (0..2 * probes.len())
        .flat_map(|view| std::iter::repeat_n(if view % 2 == 0 { above } else { below }, texels))
        .collect();
    let uniform = vec![Vec3::splat(0.8); maps.len()];
    let top = center + Vec3::new(0.0, 0.05, 0.0);
    for eye in [
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.7, 0.2, 0.1),
        Vec3::new(-0.3, 0.06, 0.2),
    ] {
        let got = reflect(
            &probes,
            &uniform,
            TILE,
            (clear, Vec3::ZERO, 0.0, 1.0),
            (top, Vec3::Y, center + eye),
        );
        assert!(
            (got - Vec3::splat(0.8)).abs().max_element() < 1e-5,
            "{got} from {eye}"
        );
    }
    let head_on = |material| {
        reflect(
            &probes,
            &maps,
            TILE,
            (material, Vec3::ZERO, 0.0, 1.0),
            (top, Vec3::Y, top + Vec3::Y),
        )
    };
    let tint = scene.materials[green as usize].base_color.truncate();
    for (material, tint) in [(clear, Vec3::ONE), (green, tint)] {
        let want = 0.04 * above + 0.96 * tint * below;
        let got = head_on(material);
        assert!((got - want).abs().max_element() < 1e-5, "{got} vs {want}");
    }
    let albedo = scene.materials[silver as usize].base_color.truncate();
    let got = reflect(
        &probes,
        &maps,
        TILE,
        (silver, albedo, 1.0, 1.0),
        (top, Vec3::Y, top + Vec3::Y),
    );
    assert!((got - albedo * above).abs().max_element() < 1e-5, "{got}");
}

/// The maps' texels against rays: from each probe through each texel centre (starting past
/// the probe's own sphere, which the cut culls as back-facing), the radiance the surfels'
/// lighting gives the first triangle hit (`ρ/π · E` by shadow rays), and the maps' CPU twin
/// against the GPU.
#[test]
fn maps_match_rays_and_the_gpu() {
    let scene = scene::mirror_spheres(8);
    let lights = lamp(&scene);
    let config = PbgiConfig {
        points_log2: 16,
        epsilon: 1.0,
        tile: TILE,
    };
    let lit = LitPoints::new(&scene, &lights, &config).expect("surfels");
    let probes = Probes::of_scene(&scene);
    let maps = lit
        .reflection_maps(&probes.centers, TILE)
        .expect("CPU maps");
    assert_eq!(maps.len(), probes.len() * 2 * (TILE * TILE) as usize);

    // The ray-cast truth.
    let bvh = scene::Bvh::build(&scene);
    let (positions, indices) = tiled_shading::rays::scene_mesh(&scene);
    let rays = tiled_shading::rays::RayBvh::new((&positions, &indices)).expect("BVH");
    let albedos = instant_radiosity::near_field::triangle_albedos(&scene);
    let first_triangle: Vec<u32> = scene
        .meshes
        .iter()
        .scan(0u32, |n, m| {
            let first = *n;
            *n += (m.indices.len() / 3) as u32;
            Some(first)
        })
        .collect();
    let reach = 2.0 * scene.bounds().diagonal();
    let unpack =
        |w: u32| Vec3::from_array([0, 1, 2].map(|i| ((w >> (8 * i)) & 0xff) as f32 / 255.0));
    // Per map texel: the radiance of the first triangles hit by 3×3 rays through it (a
    // texel's mean, as a node's radiance is its leaves' mean) and the mesh they all hit
    // (None: the rim, nothing hit, or several meshes).
    let mut truth: Vec<Option<(u32, Vec3)>> = vec![None; maps.len()];
    for (p, &center) in probes.centers.iter().enumerate() {
        let own = scene
            .meshes
            .iter()
            .filter(|m| m.name.starts_with("sphere"))
            .find(|m| m.positions[0].distance(center) < 0.1)
            .map_or(0.0, |m| {
                m.positions
                    .iter()
                    .map(|q| q.distance(center))
                    .fold(0.0, f32::max)
            });
        for half in 0..2usize {
            let normal = if half == 0 { Vec3::Y } else { Vec3::NEG_Y };
            let (tan, bit) = manylod::view::paraboloid_frame(normal);
            for t in 0..TILE * TILE {
                let (x, y) = (t % TILE, t / TILE);
                let mut hits = Vec::new();
                for s in 0..9 {
                    let sub = glam::Vec2::new((s % 3) as f32 + 0.5, (s / 3) as f32 + 0.5) / 3.0;
                    // The inverse of `map_texel`'s paraboloid.
                    let uv = (glam::Vec2::new(x as f32, y as f32) + sub) / TILE as f32 * 2.0 - 1.0;
                    let r2 = uv.length_squared();
                    if r2 >= 0.95 {
                        break; // the rim: texels only partly inside the hemisphere
                    }
                    let d = ((tan * uv.x + bit * uv.y) * 2.0 + normal * (1.0 - r2)) / (1.0 + r2);
                    let (lands, at) = map_texel(d, TILE);
                    let want = glam::Vec2::new(x as f32, y as f32) + sub;
                    assert!(lands == half && at.distance(want) < 1e-3, "{at} vs {want}");
                    let Some(hit) = bvh.closest_hit(center + d * own * 1.01, d, reach) else {
                        break;
                    };
                    let m = &scene.meshes[hit.mesh as usize];
                    let tri = &m.indices[3 * hit.triangle as usize..][..3];
                    let [a, b, c] = [0, 1, 2].map(|k| m.positions[tri[k] as usize]);
                    let mut n = (b - a).cross(c - a).normalize();
                    if n.dot(d) > 0.0 {
                        n = -n;
                    }
                    let global = first_triangle[hit.mesh as usize] + hit.triangle;
                    let rho = unpack(albedos[global as usize]);
                    let e = instant_radiosity::near_field::direct_irradiance(
                        &rays,
                        &lights,
                        reach,
                        (hit.position, n),
                    );
                    hits.push((hit.mesh, rho * e * std::f32::consts::FRAC_1_PI));
                }
                if hits.len() == 9 && hits.iter().all(|h| h.0 == hits[0].0) {
                    let mean = hits.iter().map(|h| h.1).sum::<Vec3>() / 9.0;
                    truth[(2 * p + half) * (TILE * TILE) as usize + t as usize] =
                        Some((hits[0].0, mean));
                }
            }
        }
    }
    // Away from silhouettes (the eight neighbours show the same mesh) the splat holds the
    // surface, and a texel takes the mean radiance of a node under a texel wide: it may differ
    // from the texel's own mean by the radiance's variation over the texels around (plus 10 %
    // for the surfels' lighting at their centres). At silhouettes a disc reaches up to about
    // a texel past its object (at least √½ texel).
    let texels = (TILE * TILE) as usize;
    let (mut interior, mut outside, mut err, mut sum) = (0, 0, 0.0f64, 0.0f64);
    for (i, t) in truth.iter().enumerate() {
        let Some((mesh, radiance)) = t else { continue };
        let (view, k) = (i / texels, (i % texels) as i32);
        let (x, y) = (k % TILE as i32, k / TILE as i32);
        let around: Vec<Option<(u32, Vec3)>> = (-1..=1)
            .flat_map(|dy| (-1..=1).map(move |dx| (x + dx, y + dy)))
            .map(|(nx, ny)| {
                let inside = (0..TILE as i32).contains(&nx) && (0..TILE as i32).contains(&ny);
                inside
                    .then(|| truth[view * texels + (ny * TILE as i32 + nx) as usize])
                    .flatten()
            })
            .collect();
        if !around.iter().all(|a| a.is_some_and(|(m, _)| m == *mesh)) {
            continue;
        }
        let (lo, hi) = around
            .iter()
            .flatten()
            .fold((*radiance, *radiance), |(lo, hi), (_, r)| {
                (lo.min(*r), hi.max(*r))
            });
        let got = maps[i];
        let allowed = (hi - lo) + *radiance * 0.1 + Vec3::splat(1e-4);
        interior += 1;
        outside += usize::from((got - *radiance).abs().cmpgt(allowed).any());
        err += f64::from((got - *radiance).abs().element_sum());
        sum += f64::from(radiance.element_sum());
    }
    println!(
        "reflection maps vs rays: {interior} texels away from silhouettes, mean relative error \
         {:.3}, {outside} outside the radiance's range around them",
        err / sum
    );
    assert!(interior > maps.len() / 5, "{interior} texels compared");
    assert!(
        outside * 100 <= interior * 2,
        "{outside} of {interior} texels"
    );

    let Some(gpu) = gpu::test_device(&instant_radiosity::device_needs()) else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let radiance: Vec<[f32; 4]> = lit
        .radiance
        .iter()
        .map(|r| r.extend(0.0).to_array())
        .collect();
    let radiance = gpu::transfer::buffer_init(
        d,
        "radiance",
        bytemuck::cast_slice(&radiance),
        wgpu::BufferUsages::STORAGE,
    )
    .expect("radiance");
    let mut g = GpuReflections::new(d, &lit, &radiance, (&probes, TILE), 1 << 20).expect("maps");
    let mut encoder = d.create_command_encoder(&Default::default());
    g.encode(&mut encoder, None);
    q.submit([encoder.finish()]);
    let got = g.read_maps(d, q).expect("GPU maps");
    let same = got
        .iter()
        .zip(&maps)
        .filter(|(a, b)| (**a - **b).abs().max_element() <= 1e-5)
        .count();
    println!("GPU vs CPU maps: {same} of {} texels equal", maps.len());
    let allowed = if gpu.is_software() {
        0
    } else {
        maps.len() / 200
    };
    assert!(
        maps.len() - same <= allowed,
        "{} texels differ",
        maps.len() - same
    );

    // The frame's reflection pass against its CPU twin on the GPU's maps.
    let camera = scene.camera_or_framed();
    let size = (64, 48);
    let gb = gbuffer::cpu::rasterize(&scene, &camera, size.0, size.1)
        .expect("G-buffer")
        .gbuffer;
    let frame = gbuffer::Frame::new(&camera, size.0, size.1);
    let uploaded = gbuffer::gpu::UploadedGBuffer::new(d, q, &gb, &frame).expect("upload");
    let output = gpu::transfer::texture_2d(
        d,
        "reflections",
        size.0,
        size.1,
        REFLECTION_FORMAT,
        gpu::transfer::STORAGE_ANY,
    );
    g.bind_frame(d, &uploaded.frame, uploaded.textures(), &output)
        .expect("bind");
    let mut encoder = d.create_command_encoder(&Default::default());
    g.encode(&mut encoder, None);
    q.submit([encoder.finish()]);
    let got_maps = g.read_maps(d, q).expect("maps");
    let image = interleave::gpu::download_image::<[half::f16; 4]>(d, q, &output)
        .expect("output")
        .map(|p| p.map(half::f16::to_f32));
    let (mut mirrors, mut far, mut glass) = (0, 0, 0);
    for y in 0..size.1 {
        for x in 0..size.0 {
            let word = gb.material.get(x, y);
            let want = if gb.linear_depth.get(x, y) > 0.0 && word != u32::MAX {
                let (_, metallic, material) = gbuffer::unpack_material(word);
                let (albedo, specular) = gbuffer::unpack_albedo(gb.albedo.get(x, y));
                let depth = gb.linear_depth.get(x, y);
                let p = gbuffer::position::from_view_ray(&frame, x, y, depth);
                let n = gbuffer::normal::unpack_octahedral(gb.normal.get(x, y));
                reflect(
                    &probes,
                    &got_maps,
                    TILE,
                    (material, albedo, metallic, specular),
                    (p, n, camera.eye),
                )
            } else {
                Vec3::ZERO
            };
            mirrors += usize::from(want != Vec3::ZERO);
            let word = gb.material.get(x, y);
            glass += usize::from(
                word != u32::MAX
                    && is_glass(&scene.materials[gbuffer::unpack_material(word).2 as usize]),
            );
            let g = image.get(x, y);
            if (0..3).any(|c| (g[c] - want[c]).abs() > 2e-3 * want[c].abs().max(1e-2)) {
                far += 1;
            }
        }
    }
    println!(
        "reflect pass: {mirrors} reflecting pixels ({glass} of glass), {far} differ from the \
         CPU twin"
    );
    assert!(glass > 20, "the glass spheres should show: {glass} pixels");
    assert!(
        mirrors > 50,
        "the spheres should show: {mirrors} mirror pixels"
    );
    // The texel a reflected ray picks may flip at a texel edge by rounding.
    assert!(far * 100 <= mirrors, "{far} of {mirrors} pixels differ");
}
