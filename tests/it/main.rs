//! Integration tests, in one binary to keep linking cheap on 2-core CI.

mod bad_input;
mod blender_addon;
mod bsdfs;
mod caustics;
mod cli;
mod common;
mod compare;
mod display;
mod docs;
mod environment;
mod formats;
mod gltf_accessors;
mod gltf_variants;
mod guiding;
mod lamps;
mod light_points;
mod light_samplers;
mod mutation;
mod new_user;
mod render;
mod report_page;
mod scene_loading;
mod slurm;
mod split;
mod tracers;
mod view;
