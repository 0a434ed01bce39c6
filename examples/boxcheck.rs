use myriad::light_sampler::{LightSamplerKind, LightStrategy};
use myriad::material::Material;
use myriad::math::{Mat4, Rgb, UVec2, Vec3A};
use myriad::render::{Budget, RenderSettings, render};
use myriad::scene::description::*;
use myriad::scene::shapes::box_mesh;
use myriad::scene::{BuildOptions, build};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let depth: u32 = args[1].parse().unwrap();
    let spp: u32 = args[2].parse().unwrap();
    let kind = match args[3].as_str() {
        "all" => LightSamplerKind::All,
        "uniform" => LightSamplerKind::Uniform,
        _ => LightSamplerKind::Power,
    };
    let mut mesh = box_mesh("b", Vec3A::splat(2.0), 0);
    for pair in mesh.triangles.chunks_exact_mut(2) {
        let [a, b, c] = pair[0];
        let d = pair[1][2];
        pair[0] = [a, d, c];
        pair[1] = [a, c, b];
    }
    let mat = Material { emission: Rgb::splat(0.5), double_sided: false, ..Material::diffuse("w", Rgb::splat(0.5)) };
    let mut desc = SceneDescription { source: "x".into(), materials: vec![mat], ..Default::default() };
    desc.cameras.push(CameraDesc {
        name: "c".into(),
        placement: CameraPlacement::LookAt {
            eye: Vec3A::new(0.1, -0.2, 0.3),
            target: Vec3A::new(1.0, 0.3, 0.2),
            up: Vec3A::Y,
        },
        yfov: 0.8,
        aspect_ratio: None,
    });
    desc.meshes.push(mesh);
    desc.instances.push(InstanceDesc { mesh: 0, transform: Mat4::IDENTITY, name: "b".into() });
    let scene = build(desc, &BuildOptions { resolution: Some(UVec2::new(8, 8)), camera: None }).unwrap();
    let st = LightStrategy::build(kind, &scene.lights, scene.radius);
    let out = render(
        &scene,
        &st,
        &RenderSettings {
            budget: Budget::Spp(spp),
            seed: args[4].parse().unwrap(),
            max_depth: depth,
            aovs: Default::default(),
        },
        None,
        &mut |_, _| {},
    );
    let f = &out.film;
    let (mut m, mut v) = (0.0f64, 0.0f64);
    for i in 0..64 {
        m += f.mean(i).x as f64;
        v += f.variance_of_mean(i).x as f64;
    }
    println!("mean {} se {}", m / 64.0, v.sqrt() / 64.0);
    for i in 0..64 {
        print!("{:.3} ", f.mean(i).x);
    }
    println!();
}
