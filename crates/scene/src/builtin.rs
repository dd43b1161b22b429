//! Built-in scenes: the Cornell box, many spheres on a plane, a textured checkerboard, and the
//! light-culling scenes of Ishmukhametov 2013 (walls with lights behind them).

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use crate::{Camera, Light, Material, Mesh, Scene, Texture, light::SplitMix};

/// Accumulates flat-shaded quads and smooth spheres into one mesh per material.
struct Builder {
    scene: Scene,
}

impl Builder {
    fn new() -> Self {
        Self {
            scene: Scene::default(),
        }
    }

    fn material(&mut self, name: &str, rgb: Vec3, roughness: f32, metallic: f32) -> u32 {
        self.scene.materials.push(Material {
            name: name.into(),
            base_color: rgb.extend(1.0),
            roughness,
            metallic,
            ..Default::default()
        });
        self.scene.materials.len() as u32 - 1
    }

    fn mesh(&mut self, name: &str, material: u32) -> &mut Mesh {
        self.scene.meshes.push(Mesh {
            name: name.into(),
            material,
            ..Default::default()
        });
        self.scene.meshes.last_mut().expect("just pushed")
    }

    /// A planar quad a-b-c-d with a flat normal turned to face `towards`, and UVs 0..`uv_scale`.
    fn quad(mesh: &mut Mesh, corners: [Vec3; 4], towards: Vec3, uv_scale: f32) {
        let [a, b, c, d] = corners;
        let mut n = (b - a).cross(c - a).normalize();
        let flip = n.dot(towards - (a + c) * 0.5) < 0.0;
        if flip {
            n = -n;
        }
        let base = mesh.positions.len() as u32;
        mesh.positions.extend([a, b, c, d]);
        mesh.normals.extend([n; 4]);
        mesh.uvs.extend([
            Vec2::ZERO,
            Vec2::new(uv_scale, 0.0),
            Vec2::splat(uv_scale),
            Vec2::new(0.0, uv_scale),
        ]);
        let tris = if flip {
            [0, 2, 1, 0, 3, 2]
        } else {
            [0, 1, 2, 0, 2, 3]
        };
        mesh.indices.extend(tris.map(|i| base + i));
    }

    /// A mesh "ground": the square `[-half, half]²` at y = 0 facing up, UVs 0..`uv_scale`.
    fn ground(&mut self, material: u32, half: f32, uv_scale: f32) {
        let plane = self.mesh("ground", material);
        let corner = |x: f32, z: f32| Vec3::new(x * half, 0.0, z * half);
        let corners = [
            corner(-1.0, -1.0),
            corner(1.0, -1.0),
            corner(1.0, 1.0),
            corner(-1.0, 1.0),
        ];
        Self::quad(plane, corners, Vec3::Y * 10.0, uv_scale);
    }

    /// The four sides and top of a block whose top face is `top` (at any height) and bottom is at y = 0.
    fn block(mesh: &mut Mesh, top: [Vec3; 4]) {
        let center = top.iter().copied().sum::<Vec3>() / 4.0 * Vec3::new(1.0, 0.5, 1.0);
        let away = |face: Vec3| 2.0 * face - center;
        Self::quad(mesh, top, away((top[0] + top[2]) * 0.5), 1.0);
        for i in 0..4 {
            let (p, q) = (top[i], top[(i + 1) % 4]);
            let (p0, q0) = (p * Vec3::new(1.0, 0.0, 1.0), q * Vec3::new(1.0, 0.0, 1.0));
            Self::quad(mesh, [p0, q0, q, p], away((p + q0) * 0.5), 1.0);
        }
    }

    /// A UV sphere with smooth normals.
    fn sphere(mesh: &mut Mesh, center: Vec3, radius: f32, slices: u32, stacks: u32) {
        let base = mesh.positions.len() as u32;
        for j in 0..=stacks {
            let v = j as f32 / stacks as f32;
            let theta = v * PI;
            for i in 0..=slices {
                let u = i as f32 / slices as f32;
                let phi = u * TAU;
                let n = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    -theta.sin() * phi.sin(),
                );
                mesh.positions.push(center + n * radius);
                mesh.normals.push(n);
                mesh.uvs.push(Vec2::new(u, v));
            }
        }
        let row = slices + 1;
        for j in 0..stacks {
            for i in 0..slices {
                let (a, b) = (base + j * row + i, base + (j + 1) * row + i);
                if j > 0 {
                    mesh.indices.extend([a, b, a + 1]);
                }
                if j + 1 < stacks {
                    mesh.indices.extend([a + 1, b, b + 1]);
                }
            }
        }
    }
}

/// The Cornell box with the measured dimensions of the Cornell Program of Computer Graphics
/// (in metres: 0.556 wide, 0.5488 high, 0.5592 deep; short and tall blocks; light opening
/// 0.13 × 0.105 under the ceiling), seen from its standard camera at (0.278, 0.273, −0.8)
/// with a 39.3° vertical field of view. Red wall at x = 0.556, green wall at x = 0.
/// The light opening is an emissive quad with one point light just below it.
pub fn cornell_box() -> Scene {
    let mut b = Builder::new();
    let white = b.material("white", Vec3::new(0.725, 0.71, 0.68), 0.9, 0.0);
    let red = b.material("red", Vec3::new(0.63, 0.065, 0.05), 0.9, 0.0);
    let green = b.material("green", Vec3::new(0.14, 0.45, 0.091), 0.9, 0.0);
    let light = b.material("light", Vec3::splat(0.78), 0.9, 0.0);
    b.scene.materials[light as usize].emissive = Vec3::new(17.0, 12.0, 4.0) / 17.0 * 4.0;

    let mm = |x: f32, y: f32, z: f32| Vec3::new(x, y, z) / 1000.0;
    let inside = mm(278.0, 274.4, 279.6);
    let (w, h, d) = (556.0, 548.8, 559.2);
    // A quad of the room, corners in millimetres, facing the inside.
    let wall = |mesh: &mut Mesh, corners: [[f32; 3]; 4]| {
        Builder::quad(mesh, corners.map(|[x, y, z]| mm(x, y, z)), inside, 1.0);
    };
    let room = b.mesh("room", white);
    wall(
        room,
        [[0.0, 0.0, 0.0], [w, 0.0, 0.0], [w, 0.0, d], [0.0, 0.0, d]],
    );
    wall(room, [[0.0, h, 0.0], [w, h, 0.0], [w, h, d], [0.0, h, d]]);
    wall(room, [[0.0, 0.0, d], [w, 0.0, d], [w, h, d], [0.0, h, d]]);
    let red_wall = b.mesh("red wall", red);
    wall(
        red_wall,
        [[w, 0.0, 0.0], [w, 0.0, d], [w, h, d], [w, h, 0.0]],
    );
    let green_wall = b.mesh("green wall", green);
    wall(
        green_wall,
        [[0.0, 0.0, 0.0], [0.0, 0.0, d], [0.0, h, d], [0.0, h, 0.0]],
    );
    let blocks = b.mesh("blocks", white);
    // The short and the tall block, by their tops.
    let short = [(130.0, 65.0), (82.0, 225.0), (240.0, 272.0), (290.0, 114.0)];
    let tall = [
        (423.0, 247.0),
        (265.0, 296.0),
        (314.0, 456.0),
        (472.0, 406.0),
    ];
    for (top, y) in [(short, 165.0), (tall, 330.0)] {
        Builder::block(blocks, top.map(|(x, z)| mm(x, y, z)));
    }
    let lamp = b.mesh("light", light);
    let ly = h - 1.0;
    wall(
        lamp,
        [
            [343.0, ly, 227.0],
            [213.0, ly, 227.0],
            [213.0, ly, 332.0],
            [343.0, ly, 332.0],
        ],
    );

    b.scene.lights.push(Light::Point {
        position: mm(278.0, 500.0, 279.5),
        color: Vec3::new(1.0, 0.85, 0.65),
        intensity: 0.12,
        radius: 1.2,
    });
    b.scene.camera = Some(Camera {
        eye: mm(278.0, 273.0, -800.0),
        target: mm(278.0, 273.0, 0.0),
        up: Vec3::Y,
        fov_y: 39.3077f32.to_radians(),
        near: 0.05,
        far: 3.0,
    });
    b.scene
}

/// The Cornell box without its blocks, holding `n` (1..=4096) spheres on a lattice that fills
/// the middle of the room, in turn silver, gold, clear glass and green glass (roughness 0.05;
/// the glass transmits all, ior 1.5), each sphere its own mesh: the set-up of Holländer 2013
/// Fig. 3.19 (hundreds of reflecting and refracting objects, each with its own map).
pub fn mirror_spheres(n: u32) -> Scene {
    let n = n.clamp(1, 4096);
    let mut scene = cornell_box();
    scene.meshes.retain(|m| m.name != "blocks");
    let mut b = Builder { scene };
    let finishes = [
        ("silver", Vec3::new(0.97, 0.96, 0.91), 1.0),
        ("gold", Vec3::new(1.0, 0.78, 0.34), 1.0),
        ("glass", Vec3::ONE, 0.0),
        ("green glass", Vec3::new(0.55, 0.9, 0.6), 0.0),
    ]
    .map(|(name, rgb, metallic)| {
        let m = b.material(name, rgb, 0.05, metallic);
        if metallic == 0.0 {
            b.scene.materials[m as usize].transmission = 1.0;
        }
        m
    });
    let k = (n as f32).cbrt().ceil() as u32;
    let (lo, hi) = (Vec3::new(0.1, 0.06, 0.12), Vec3::new(0.456, 0.44, 0.48));
    let spacing = (hi - lo) / k as f32;
    let radius = 0.3 * spacing.min_element();
    for i in 0..n {
        let cell = Vec3::new((i % k) as f32, ((i / k) % k) as f32, (i / (k * k)) as f32);
        let mesh = b.mesh(&format!("sphere {i}"), finishes[i as usize % 4]);
        Builder::sphere(mesh, lo + (cell + 0.5) * spacing, radius, 24, 12);
    }
    b.scene
}

/// An `n × n` grid of spheres (radius 0.4, spacing 1) on a ground plane, with materials that
/// vary in colour, roughness and metalness, and `n` scattered point lights.
pub fn spheres_on_plane(n: u32) -> Scene {
    let n = n.clamp(1, 256);
    let mut b = Builder::new();
    let ground = b.material("ground", Vec3::splat(0.6), 0.7, 0.0);
    let half = n as f32 * 0.5 + 1.0;
    b.ground(ground, half, 1.0);
    let mut rng = SplitMix(7);
    for k in 0..8u32 {
        let rgb = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 0.8 + 0.1;
        b.material(
            &format!("sphere {k}"),
            rgb,
            0.15 + 0.1 * k as f32,
            if k % 3 == 0 { 1.0 } else { 0.0 },
        );
    }
    for k in 0..8u32 {
        let mesh = b.mesh(&format!("spheres {k}"), 1 + k);
        for i in 0..n * n {
            if i % 8 != k {
                continue;
            }
            let (x, z) = (
                (i % n) as f32 - (n as f32 - 1.0) * 0.5,
                (i / n) as f32 - (n as f32 - 1.0) * 0.5,
            );
            Builder::sphere(mesh, Vec3::new(x, 0.4, z), 0.4, 24, 12);
        }
    }
    b.scene.meshes.retain(|m| !m.indices.is_empty());
    let bounds = b.scene.bounds();
    b.scene.lights = crate::scatter_point_lights(bounds, n as usize, 11);
    let mut cam = Camera::look_at(
        Vec3::new(0.0, n as f32 * 0.6 + 1.0, n as f32 * 0.9 + 2.0),
        Vec3::ZERO,
    );
    cam.fit_planes(bounds);
    b.scene.camera = Some(cam);
    b.scene
}

/// A point light of `radius` and `color` whose intensity `radius²/4` gives about unit
/// illuminance at half the radius (as [`crate::scatter_point_lights`]).
fn bounded_light(position: Vec3, color: Vec3, radius: f32) -> Light {
    Light::Point {
        position,
        color,
        intensity: radius * radius * 0.25,
        radius,
    }
}

/// Uniform (seeded) point in the box `min..max`.
fn point_in(rng: &mut SplitMix, min: Vec3, max: Vec3) -> Vec3 {
    min + (max - min) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32())
}

/// Radius of the point lights of [`thesis_walls`].
pub const THESIS_LIGHT_RADIUS: f32 = 6.0;
/// Lights of [`thesis_walls`] inside the view in front of the walls.
pub const THESIS_VISIBLE_LIGHTS: u32 = 55;
/// Lights of [`thesis_walls`] outside the view frustum (behind the camera).
pub const THESIS_HIDDEN_LIGHTS: u32 = 1445;

/// The test scene of Ishmukhametov 2013 §4.2, rebuilt: a large courtyard (floor 200 m × 160 m,
/// a back wall 120 m × 30 m facing the camera 32 m away and filling most of its 60° view, side
/// walls, a row of pillars). Point lights of radius 6 m: 55 in front of the
/// back wall inside the view, 1445 outside the view frustum behind the camera (what CPU
/// frustum culling removes), and `behind` just behind the back wall (0.3–0.9 radii deep,
/// inside the view's frustum and reaching the wall's depth): they face the back of the wall,
/// so normal-cone culling can reject them where the wall fills a tile. The thesis's tests 1–4
/// are `behind` = 0, 100, 500, 1000 (1500, 1600, 2000, 2500 lights).
pub fn thesis_walls(behind: u32) -> Scene {
    let mut b = Builder::new();
    let floor_m = b.material("floor", Vec3::splat(0.5), 0.8, 0.0);
    let wall_m = b.material("walls", Vec3::new(0.7, 0.65, 0.6), 0.6, 0.0);
    let pillar_m = b.material("pillars", Vec3::new(0.55, 0.6, 0.7), 0.4, 0.0);
    let v = Vec3::new;
    let floor = b.mesh("floor", floor_m);
    Builder::quad(
        floor,
        [
            v(-100.0, 0.0, -100.0),
            v(100.0, 0.0, -100.0),
            v(100.0, 0.0, 60.0),
            v(-100.0, 0.0, 60.0),
        ],
        Vec3::Y * 10.0,
        40.0,
    );
    let walls = b.mesh("walls", wall_m);
    // The back wall, 1 m thick: a front face (z = −40) towards the camera and a back face.
    for (z, towards) in [(-40.0, 0.0), (-41.0, -80.0)] {
        let face =
            [(-60.0, 0.0), (60.0, 0.0), (60.0, 30.0), (-60.0, 30.0)].map(|(x, y)| v(x, y, z));
        Builder::quad(walls, face, v(0.0, 10.0, towards), 12.0);
    }
    for x in [-30.0f32, 30.0] {
        Builder::quad(
            walls,
            [
                v(x, 0.0, -40.0),
                v(x, 0.0, 0.0),
                v(x, 12.0, 0.0),
                v(x, 12.0, -40.0),
            ],
            v(0.0, 5.0, -20.0),
            4.0,
        );
    }
    let pillars = b.mesh("pillars", pillar_m);
    for i in 0..6 {
        let x = -20.0 + 8.0 * i as f32;
        let z = -25.0;
        Builder::block(
            pillars,
            [
                v(x - 0.8, 8.0, z - 0.8),
                v(x + 0.8, 8.0, z - 0.8),
                v(x + 0.8, 8.0, z + 0.8),
                v(x - 0.8, 8.0, z + 0.8),
            ],
        );
    }
    let r = THESIS_LIGHT_RADIUS;
    let mut rng = SplitMix(1500);
    let color = |rng: &mut SplitMix| v(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 0.7 + 0.3;
    let mut lights = Vec::new();
    for _ in 0..THESIS_VISIBLE_LIGHTS {
        let c = color(&mut rng);
        lights.push(bounded_light(
            point_in(&mut rng, v(-25.0, 0.5, -38.0), v(25.0, 16.0, -14.0)),
            c,
            r,
        ));
    }
    for _ in 0..THESIS_HIDDEN_LIGHTS {
        let c = color(&mut rng);
        lights.push(bounded_light(
            point_in(&mut rng, v(-100.0, 0.5, 20.0), v(100.0, 20.0, 60.0)),
            c,
            r,
        ));
    }
    for _ in 0..behind {
        let c = color(&mut rng);
        lights.push(bounded_light(
            point_in(
                &mut rng,
                v(-25.0, 1.0, -40.0 - 0.9 * r),
                v(25.0, 16.0, -40.0 - 0.3 * r),
            ),
            c,
            r,
        ));
    }
    b.scene.lights = lights;
    let mut cam = Camera::look_at(v(0.0, 10.0, -8.0), v(0.0, 10.0, -40.0));
    cam.fov_y = 60f32.to_radians();
    cam.near = 0.5;
    cam.far = 250.0;
    b.scene.camera = Some(cam);
    b.scene
}

/// A wall (100 m square at z = −10, facing +Z) filling the view of a camera at the origin
/// looking down −Z, with `front` point lights of radius 3 m between the camera and the wall
/// and `behind` lights behind it (0.4–0.9 radii deep, within reach of the wall's depth): the
/// normal-cone culling test must remove exactly the lights behind. Lights are listed front
/// first.
pub fn wall(front: u32, behind: u32) -> Scene {
    let mut b = Builder::new();
    let m = b.material("wall", Vec3::splat(0.7), 0.5, 0.0);
    let mesh = b.mesh("wall", m);
    let v = Vec3::new;
    Builder::quad(
        mesh,
        [
            v(-50.0, -50.0, -10.0),
            v(50.0, -50.0, -10.0),
            v(50.0, 50.0, -10.0),
            v(-50.0, 50.0, -10.0),
        ],
        Vec3::ZERO,
        10.0,
    );
    let r = 3.0;
    let mut rng = SplitMix(10);
    let mut lights = Vec::new();
    for _ in 0..front {
        lights.push(bounded_light(
            point_in(&mut rng, v(-4.0, -3.0, -9.5), v(4.0, 3.0, -6.0)),
            Vec3::ONE,
            r,
        ));
    }
    for _ in 0..behind {
        lights.push(bounded_light(
            point_in(
                &mut rng,
                v(-4.0, -3.0, -10.0 - 0.9 * r),
                v(4.0, 3.0, -10.0 - 0.4 * r),
            ),
            Vec3::ONE,
            r,
        ));
    }
    b.scene.lights = lights;
    let mut cam = Camera::look_at(Vec3::ZERO, v(0.0, 0.0, -10.0));
    cam.near = 0.5;
    cam.far = 50.0;
    b.scene.camera = Some(cam);
    b.scene
}

/// A 256 × 256 two-tone checker (32-texel squares, sRGB 230 and 26), the built-in texture.
pub fn checker_texture() -> Texture {
    let size = 256u32;
    let rgba8 = (0..size * size)
        .flat_map(|i| {
            let (x, y) = (i % size, i / size);
            let v = if ((x / 32) + (y / 32)) % 2 == 0 {
                230
            } else {
                26
            };
            [v, v, v, 255]
        })
        .collect();
    Texture {
        name: "checker".into(),
        width: size,
        height: size,
        rgba8,
        sampler: Default::default(),
    }
}

/// A 40 × 40 ground plane textured with a checkerboard repeated 20 times (so checks alias
/// towards the horizon), with boxes and spheres on it, seen from a low grazing camera; one
/// directional and two point lights. For texture-filtering and aliasing tests.
pub fn checkerboard() -> Scene {
    let mut b = Builder::new();
    b.scene.textures.push(checker_texture());
    let ground = b.material("checker", Vec3::ONE, 0.6, 0.0);
    b.scene.materials[ground as usize].base_color_texture = Some(crate::TextureRef::new(0));
    let boxes = b.material("boxes", Vec3::new(0.8, 0.35, 0.1), 0.4, 0.0);
    let balls = b.material("balls", Vec3::new(0.9, 0.9, 0.95), 0.2, 1.0);
    let s = 20.0;
    b.ground(ground, s, 20.0);
    let cubes = b.mesh("boxes", boxes);
    for (x, z, e) in [(-2.0, -3.0, 0.8), (1.5, -6.0, 1.2), (4.0, -12.0, 1.5)] {
        let c = [
            Vec3::new(x - e, 2.0 * e, z - e),
            Vec3::new(x + e, 2.0 * e, z - e),
            Vec3::new(x + e, 2.0 * e, z + e),
            Vec3::new(x - e, 2.0 * e, z + e),
        ];
        Builder::block(cubes, c);
    }
    let spheres = b.mesh("balls", balls);
    for (x, z, r) in [(0.0, -1.0, 0.7), (-4.0, -8.0, 1.0), (3.0, -3.0, 0.5)] {
        Builder::sphere(spheres, Vec3::new(x, r, z), r, 32, 16);
    }
    b.scene.lights.push(Light::Directional {
        direction: Vec3::new(-0.4, -1.0, -0.3).normalize(),
        color: Vec3::ONE,
        intensity: 1.0,
    });
    b.scene.lights.push(Light::Point {
        position: Vec3::new(-1.0, 2.0, 0.0),
        color: Vec3::new(1.0, 0.6, 0.3),
        intensity: 2.0,
        radius: 8.0,
    });
    b.scene.lights.push(Light::Point {
        position: Vec3::new(3.0, 3.0, -7.0),
        color: Vec3::new(0.3, 0.6, 1.0),
        intensity: 4.0,
        radius: 12.0,
    });
    b.scene.camera = Some(Camera {
        eye: Vec3::new(0.0, 1.6, 4.0),
        target: Vec3::new(0.0, 0.6, -6.0),
        up: Vec3::Y,
        fov_y: 50f32.to_radians(),
        near: 0.1,
        far: 80.0,
    });
    b.scene
}

/// A `size`² texture whose texel (x, y) is `texel(x / size, y / size)` (coordinates of the
/// texel's centre in \[0, 1\]), RGBA8.
fn procedural(name: &str, size: u32, texel: impl Fn(f32, f32) -> [u8; 4]) -> Texture {
    let rgba8 = (0..size * size)
        .flat_map(|i| {
            let (x, y) = (i % size, i / size);
            texel(
                (x as f32 + 0.5) / size as f32,
                (y as f32 + 0.5) / size as f32,
            )
        })
        .collect();
    Texture {
        name: name.into(),
        width: size,
        height: size,
        rgba8,
        sampler: Default::default(),
    }
}

/// The distance of (u, v) to the nearest mortar line of a running-bond brick wall of 4 courses
/// and 2 bricks per course per tile, in units of the tile (0 on the mortar's centre line),
/// and the direction from the line into the brick.
fn brick(u: f32, v: f32) -> (f32, Vec2) {
    let course = (v * 4.0).floor();
    let shift = if course as i32 % 2 == 0 { 0.0 } else { 0.25 };
    let bu = (u + shift).rem_euclid(0.5) / 0.5;
    let bv = (v * 4.0).fract();
    // Distances to the four edges of the brick, in tile units.
    let edges = [
        (bu * 0.5, Vec2::X),
        ((1.0 - bu) * 0.5, -Vec2::X),
        (bv * 0.25, Vec2::Y),
        ((1.0 - bv) * 0.25, -Vec2::Y),
    ];
    edges
        .into_iter()
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .expect("four edges")
}

/// The brick wall's tangent-space normal map: a bevel 0.04 tile units wide along the mortar
/// lines tilts the normal 45° away from them (128², linear).
fn bricks_normal_map() -> Texture {
    procedural("bricks-normal", 128, |u, v| {
        let (d, inward) = brick(u, v);
        let slope = if d < 0.04 { 1.0 } else { 0.0 };
        let n = Vec3::new(-inward.x * slope, -inward.y * slope, 1.0).normalize();
        let e = |c: f32| ((c * 0.5 + 0.5) * 255.0).round() as u8;
        [e(n.x), e(n.y), e(n.z), 255]
    })
}

/// The brick wall's ambient occlusion: 0.2 in the mortar, rising to 1 across the bevel.
fn bricks_occlusion() -> Texture {
    procedural("bricks-occlusion", 128, |u, v| {
        let o = ((brick(u, v).0 / 0.04).clamp(0.2, 1.0) * 255.0) as u8;
        [o, o, o, 255]
    })
}

/// Brick and mortar colours (sRGB), the bricks varying in tone.
fn bricks_colour() -> Texture {
    procedural("bricks", 128, |u, v| {
        if brick(u, v).0 < 0.02 {
            return [170, 165, 150, 255];
        }
        let course = (v * 4.0).floor();
        let n = ((u * 2.0 + course * 0.5).floor() * 7.0 + course * 3.0).rem_euclid(5.0) as u8;
        [150 + 12 * n, 70 + 6 * n, 50 + 3 * n, 255]
    })
}

/// Replaces `scene`'s materials with procedural normal-mapped ones, for scenes that come
/// without textures (the shared Sponza): meshes facing mostly up or down get floor tiles
/// (base colour and a grout normal map), the rest brick walls (base colour, normal map and
/// ambient occlusion). Texture coordinates are the scene's own; tangents are generated
/// (MikkTSpace). The issue-22 test scene for interleaved indirect light on normal-mapped
/// surfaces (Segovia et al. 2006, Fig. 7).
pub fn dress_procedurally(scene: &mut Scene) {
    use crate::TextureRef;
    let first = scene.textures.len() as u32;
    scene.textures.extend([
        bricks_colour(),
        bricks_normal_map(),
        bricks_occlusion(),
        procedural("floor-tiles", 128, |u, v| {
            let grout = (u * 4.0).fract() < 0.05 || (v * 4.0).fract() < 0.05;
            let tone = if ((u * 4.0) as u32 + (v * 4.0) as u32) % 2 == 0 {
                200
            } else {
                160
            };
            if grout {
                [90, 85, 80, 255]
            } else {
                [tone, tone - 15, tone - 40, 255]
            }
        }),
        procedural("floor-tiles-normal", 128, |u, v| {
            let (fu, fv) = ((u * 4.0).fract(), (v * 4.0).fract());
            let d = [fu, 1.0 - fu, fv, 1.0 - fv];
            let k = (0..4).min_by(|&a, &b| d[a].total_cmp(&d[b])).unwrap_or(0);
            let slope = if d[k] < 0.05 { 0.7 } else { 0.0 };
            let inward = [Vec2::X, -Vec2::X, Vec2::Y, -Vec2::Y][k];
            let n = Vec3::new(-inward.x * slope, -inward.y * slope, 1.0).normalize();
            let e = |c: f32| ((c * 0.5 + 0.5) * 255.0).round() as u8;
            [e(n.x), e(n.y), e(n.z), 255]
        }),
    ]);
    let texture = |k: u32| Some(TextureRef::new(first + k));
    let walls = scene.materials.len() as u32;
    scene.materials.push(Material {
        name: "procedural bricks".into(),
        base_color: Vec3::ONE.extend(1.0),
        base_color_texture: texture(0),
        normal_texture: texture(1),
        occlusion_texture: texture(2),
        roughness: 0.85,
        specular: 0.5,
        ..Default::default()
    });
    scene.materials.push(Material {
        name: "procedural floor tiles".into(),
        base_color: Vec3::ONE.extend(1.0),
        base_color_texture: texture(3),
        normal_texture: texture(4),
        roughness: 0.45,
        ..Default::default()
    });
    for mesh in &mut scene.meshes {
        let mut up = 0.0;
        let mut total = 0.0;
        for t in mesh.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[t[k] as usize]);
            let n = (b - a).cross(c - a);
            up += n.y.abs();
            total += n.length();
        }
        let floor = total > 0.0 && up / total > 0.7;
        mesh.material = walls + u32::from(floor);
        mesh.tangents.clear();
    }
    scene.complete_tangents();
}

/// The material gallery: ten spheres on a checker ground, each showing one part of the glTF
/// metallic-roughness material (issue 22), with procedural textures made here. Front row, left
/// to right: base colour texture (tiles), metallic-roughness texture (metal left, roughness
/// rising upwards), normal map (bricks), occlusion texture (the bricks' mortar), emissive
/// texture (rings). Back row: vertex colours, texture-coordinate set 1 with a texture
/// transform, alpha `MASK` (holes), alpha `BLEND` (half transparent, dithered), and an open
/// one-sided hemisphere (its inside is culled). The ground's checker is rotated by a texture
/// transform. One directional and one point light.
pub fn material_gallery() -> Scene {
    use crate::{AlphaMode, TextureRef, UvTransform};
    let mut b = Builder::new();
    let textures = [
        procedural("tiles", 128, |u, v| {
            let (i, j) = ((u * 4.0) as u32, (v * 4.0) as u32);
            let hues = [[200, 60, 40], [40, 140, 200], [230, 190, 60], [60, 170, 80]];
            let c = hues[((i + 2 * j) % 4) as usize];
            let grout = (u * 4.0).fract() < 0.08 || (v * 4.0).fract() < 0.08;
            if grout {
                [230, 230, 220, 255]
            } else {
                [c[0], c[1], c[2], 255]
            }
        }),
        procedural("metal-rough", 64, |u, v| {
            [
                0,
                ((1.0 - v) * 255.0) as u8,
                if u < 0.5 { 255 } else { 0 },
                255,
            ]
        }),
        bricks_normal_map(),
        bricks_occlusion(),
        procedural("rings", 128, |u, v| {
            let r = Vec2::new(u - 0.5, v - 0.5).length() * 8.0;
            if r.fract() < 0.5 {
                [255, 150, 40, 255]
            } else {
                [0, 0, 0, 255]
            }
        }),
        procedural("holes", 64, |u, v| {
            let hole = Vec2::new((u * 4.0).fract() - 0.5, (v * 4.0).fract() - 0.5).length() < 0.3;
            [200, 200, 210, if hole { 0 } else { 255 }]
        }),
    ];
    b.scene.textures.push(checker_texture());
    b.scene.textures.extend(textures);
    let texture = |t: u32| Some(TextureRef::new(t));
    let ground = b.material("checker", Vec3::ONE, 0.7, 0.0);
    b.scene.materials[ground as usize].base_color_texture = Some(TextureRef {
        transform: UvTransform {
            rotation: 30f32.to_radians(),
            ..UvTransform::IDENTITY
        },
        ..TextureRef::new(0)
    });
    b.ground(ground, 12.0, 12.0);
    let spheres: [(&str, Box<dyn Fn(&mut Material)>); 10] = [
        (
            "base colour texture",
            Box::new(|m| m.base_color_texture = texture(1)),
        ),
        (
            "metallic-roughness texture",
            Box::new(|m| {
                m.metallic_roughness_texture = texture(2);
                m.metallic = 1.0;
                m.roughness = 1.0;
                m.base_color = Vec3::new(0.95, 0.64, 0.54).extend(1.0);
            }),
        ),
        (
            "normal map",
            Box::new(|m| {
                m.normal_texture = texture(3);
                m.base_color = Vec3::new(0.6, 0.25, 0.15).extend(1.0);
            }),
        ),
        (
            "occlusion texture",
            Box::new(|m| {
                m.occlusion_texture = texture(4);
                m.occlusion_strength = 1.0;
            }),
        ),
        (
            "emissive texture",
            Box::new(|m| {
                m.emissive_texture = texture(5);
                m.emissive = Vec3::splat(2.0);
                m.base_color = Vec3::splat(0.2).extend(1.0);
            }),
        ),
        ("vertex colours", Box::new(|_| ())),
        (
            "texture-coordinate set 1",
            Box::new(|m| {
                m.base_color_texture = Some(TextureRef {
                    texture: 0,
                    uv_set: 1,
                    transform: UvTransform {
                        offset: Vec2::new(0.25, 0.0),
                        rotation: 45f32.to_radians(),
                        scale: Vec2::splat(2.0),
                    },
                });
            }),
        ),
        (
            "alpha mask",
            Box::new(|m| {
                m.base_color_texture = texture(6);
                m.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
            }),
        ),
        (
            "alpha blend",
            Box::new(|m| {
                m.base_color = Vec3::new(0.2, 0.5, 0.9).extend(0.5);
                m.alpha_mode = AlphaMode::Blend;
            }),
        ),
        ("one-sided", Box::new(|m| m.double_sided = false)),
    ];
    for (k, (name, style)) in spheres.iter().enumerate() {
        let material = b.material(name, Vec3::splat(0.8), 0.5, 0.0);
        style(&mut b.scene.materials[material as usize]);
        let (column, row) = ((k % 5) as f32, (k / 5) as f32);
        let center = Vec3::new((column - 2.0) * 1.25, 0.5, -row * 1.4);
        let mesh = b.mesh(name, material);
        Builder::sphere(mesh, center, 0.5, 48, 24);
        if *name == "one-sided" {
            // Open at the top, so the camera looks at its inside.
            let positions = &mesh.positions;
            let tris: Vec<u32> = mesh
                .indices
                .chunks_exact(3)
                .filter(|t| {
                    t.iter().map(|&i| positions[i as usize].y).sum::<f32>() < 3.0 * (center.y + 0.2)
                })
                .flatten()
                .copied()
                .collect();
            mesh.indices = tris;
        }
        if *name == "vertex colours" {
            mesh.colors = mesh
                .positions
                .iter()
                .map(|p| {
                    let h = (p.y - center.y) / 0.5 * 0.5 + 0.5;
                    Vec3::new(h, 1.0 - h, 0.5 + 0.5 * (p.x - center.x) / 0.5).extend(1.0)
                })
                .collect();
        }
        if *name == "texture-coordinate set 1" {
            mesh.uvs1 = mesh
                .positions
                .iter()
                .map(|p| Vec2::new(p.x, p.y) * 0.5)
                .collect();
        }
    }
    b.scene.complete_tangents();
    b.scene.lights.push(Light::Directional {
        direction: Vec3::new(-0.5, -1.0, -0.6).normalize(),
        color: Vec3::ONE,
        intensity: 2.0,
    });
    b.scene.lights.push(Light::Point {
        position: Vec3::new(2.5, 2.0, 1.5),
        color: Vec3::new(1.0, 0.8, 0.6),
        intensity: 3.0,
        radius: 10.0,
    });
    b.scene.camera = Some(Camera {
        eye: Vec3::new(0.0, 2.3, 4.4),
        target: Vec3::new(0.0, 0.25, -0.7),
        up: Vec3::Y,
        fov_y: 45f32.to_radians(),
        near: 0.1,
        far: 40.0,
    });
    b.scene
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every mesh of a dressed scene gets a normal-mapped material and unit tangents, floors
    /// (the Cornell box's floor and ceiling) the tiles, walls the bricks.
    #[test]
    fn dressing_gives_every_mesh_a_normal_mapped_material() {
        let mut s = cornell_box();
        dress_procedurally(&mut s);
        s.validate().expect("valid");
        for m in &s.meshes {
            let material = &s.materials[m.material as usize];
            assert!(material.normal_texture.is_some(), "{}", m.name);
            assert_eq!(m.tangents.len(), m.positions.len(), "{}", m.name);
            assert!(
                m.tangents
                    .iter()
                    .all(|t| (t.truncate().length() - 1.0).abs() < 1e-3)
            );
            let all = |f: fn(f32) -> bool| m.normals.iter().all(|n| f(n.y.abs()));
            if all(|y| y > 0.9) {
                assert_eq!(material.name, "procedural floor tiles", "{}", m.name);
            } else if all(|y| y < 0.1) {
                assert_eq!(material.name, "procedural bricks", "{}", m.name);
            }
        }
    }

    #[test]
    fn builtins_validate() {
        for scene in [
            cornell_box(),
            spheres_on_plane(4),
            checkerboard(),
            material_gallery(),
        ] {
            scene.validate().expect("built-in scene is valid");
        }
    }

    #[test]
    fn cornell_box_has_its_measured_extent() {
        let b = cornell_box().bounds();
        assert!((b.min - Vec3::ZERO).abs().max_element() < 1e-6);
        assert!(
            (b.max - Vec3::new(0.556, 0.5488, 0.5592))
                .abs()
                .max_element()
                < 1e-6
        );
    }

    #[test]
    fn room_normals_face_inwards_and_block_normals_outwards() {
        let s = cornell_box();
        let inside = Vec3::new(0.278, 0.274, 0.28);
        for m in s.meshes.iter().filter(|m| m.name != "blocks") {
            for (p, n) in m.positions.iter().zip(&m.normals) {
                assert!(
                    n.dot(inside - *p) > 0.0,
                    "{}: normal {n} at {p} faces out",
                    m.name
                );
            }
        }
        let blocks = s
            .meshes
            .iter()
            .find(|m| m.name == "blocks")
            .expect("blocks");
        // Every block face normal points away from the nearer block's vertical axis.
        for t in blocks.indices.chunks_exact(3) {
            let c = t
                .iter()
                .map(|&i| blocks.positions[i as usize])
                .sum::<Vec3>()
                / 3.0;
            let (short, tall) = (
                Vec3::new(0.1855, c.y, 0.169),
                Vec3::new(0.3685, c.y, 0.35125),
            );
            let axis = if c.distance(short) < c.distance(tall) {
                short
            } else {
                tall
            };
            let n = blocks.normals[t[0] as usize];
            assert!(
                n.dot(c - axis) > 0.0 || n.y > 0.9,
                "block normal {n} at {c}"
            );
        }
    }

    #[test]
    fn winding_agrees_with_normals() {
        for scene in [cornell_box(), spheres_on_plane(3), checkerboard()] {
            for m in &scene.meshes {
                for t in m.indices.chunks_exact(3) {
                    let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
                    let geometric = (b - a).cross(c - a);
                    if geometric.length() < 1e-9 {
                        continue;
                    }
                    let shading = m.normals[t[0] as usize]
                        + m.normals[t[1] as usize]
                        + m.normals[t[2] as usize];
                    assert!(
                        geometric.dot(shading) > 0.0,
                        "{}: triangle winding disagrees with normals",
                        m.name
                    );
                }
            }
        }
    }

    #[test]
    fn checker_texture_is_two_tone() {
        let t = checker_texture();
        assert_eq!(t.rgba8.len(), 256 * 256 * 4);
        assert_eq!(t.rgba8[0], 230);
        assert_eq!(t.rgba8[32 * 4], 26);
    }
}
