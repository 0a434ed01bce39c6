//! # myriad
//!
//! A physically based CPU path tracer for scenes lit by very many light sources.
//!
//! Data flows one way: a scene file is read by [`io`] into a plain
//! [`scene::SceneDescription`]; [`scene::build`] validates it, turns emissive surfaces into
//! [`light::Light`]s and builds the BVH ([`geometry`]); [`light_sampler::LightStrategy::build`]
//! prepares the light sampler chosen by name; [`render::render`] traces paths
//! ([`integrator`]) over rayon with counter-based random numbers ([`sampling`]) into a
//! [`film::Film`]; [`io::exr`] writes the result. [`commands`] strings these together the way
//! the `myriad` binary does.
//!
//! ```
//! use myriad::{commands, light_sampler::LightStrategy, settings::LightSamplerKind, render, scene::BuildOptions};
//! use myriad::math::UVec2;
//!
//! // The built-in Cornell box, tiny and quick.
//! let opts = BuildOptions { resolution: Some(UVec2::new(16, 12)), camera: None, ..Default::default() };
//! let scene = commands::load_scene(None, &opts.clone().into()).unwrap().scene;
//! let strategy = LightStrategy::build(LightSamplerKind::Power, &scene.lights, scene.center, scene.radius);
//! let settings = render::RenderSettings {
//!     budget: render::Budget::Spp(4),
//!     seed: 1,
//!     max_depth: 4,
//!     clamp: myriad::settings::Clamp::OFF,
//!     guiding: false,
//!     caustics: true,
//!     resolution: UVec2::new(16, 12),
//!     aovs: Default::default(),
//! };
//! let out = render::render(&scene, &strategy, &settings, &mut ());
//! assert_eq!(out.stats.spp, 4);
//! assert!(out.film.means().iter().any(|p| p.max_element() > 0.0));
//! ```

pub mod camera;
pub mod commands;
pub mod compare;
pub mod cpu;
pub mod error;
pub mod film;
pub mod fingerprint;
pub mod geometry;
pub mod guard;
pub mod guiding;
pub mod image;
pub mod integrator;
pub mod interrupt;
pub mod io;
pub mod learning;
pub mod light;
pub mod light_sampler;
pub mod limits;
pub mod material;
pub mod math;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod settings;

pub use error::{Error, Result};
