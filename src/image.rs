//! Float images as files hold them: named channels of one size ([`Layers`]), what a render
//! writes ([`crate::film::Film::layers`]) and what the EXR reader returns.
//!
//! Channel names follow EXR: `R`, `G`, `B` for the picture, `prefix.R` … for a colour layer
//! (`albedo.R`, `variance.G`), single names for the rest (`Z`, `N.X`).

use crate::math::{Rgb, UVec2};

/// A named single-channel image (row-major, top row first).
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// EXR channel name (`R`, `albedo.G`, `variance.B`, `Z`…).
    pub name: String,
    /// One value per pixel, `size.x × size.y` of them.
    pub data: Vec<f32>,
}

/// An image made of named channels, all of one size.
#[derive(Clone, Debug, PartialEq)]
pub struct Layers {
    /// Width and height.
    pub size: UVec2,
    /// Channels in file order, each of `size`.
    pub channels: Vec<Channel>,
}

/// The name of channel `c` (`R`, `G` or `B`) of the colour layer `prefix` ("" for the picture).
fn colour_channel(prefix: &str, c: &str) -> String {
    if prefix.is_empty() { c.to_string() } else { format!("{prefix}.{c}") }
}

impl Layers {
    /// No channels yet.
    pub fn new(size: UVec2) -> Self {
        Self { size, channels: Vec::new() }
    }

    /// The channel called `name`.
    pub fn channel(&self, name: &str) -> Option<&Channel> {
        self.channels.iter().find(|c| c.name == name)
    }

    /// Adds one channel.
    pub fn push(&mut self, name: impl Into<String>, data: Vec<f32>) {
        self.channels.push(Channel { name: name.into(), data });
    }

    /// Adds the three channels `names` holding the components of `values`.
    pub fn push_vectors(&mut self, names: [&str; 3], values: &[Rgb]) {
        for (c, name) in names.into_iter().enumerate() {
            self.push(name, values.iter().map(|v| v[c]).collect());
        }
    }

    /// Adds the colour layer `prefix` ("" for the picture's R, G, B).
    pub fn push_rgb(&mut self, prefix: &str, values: &[Rgb]) {
        let names = ["R", "G", "B"].map(|c| colour_channel(prefix, c));
        self.push_vectors([&names[0], &names[1], &names[2]], values);
    }

    /// The colour layer `prefix` ("" for the picture), if all three channels are present.
    pub fn rgb_layer(&self, prefix: &str) -> Option<Vec<Rgb>> {
        let [r, g, b] = ["R", "G", "B"].map(|c| self.channel(&colour_channel(prefix, c)));
        let (r, g, b) = (r?, g?, b?);
        Some((0..r.data.len()).map(|i| Rgb::new(r.data[i], g.data[i], b.data[i])).collect())
    }

    /// The picture's R, G, B channels as colours, if present.
    pub fn rgb(&self) -> Option<Vec<Rgb>> {
        self.rgb_layer("")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_layers_read_back_what_was_pushed() {
        let mut layers = Layers::new(UVec2::new(2, 1));
        let (picture, variance) = ([Rgb::new(1.0, 2.0, 3.0), Rgb::ZERO], [Rgb::ONE, Rgb::splat(0.5)]);
        layers.push_rgb("", &picture);
        layers.push_rgb("variance", &variance);
        let names: Vec<&str> = layers.channels.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["R", "G", "B", "variance.R", "variance.G", "variance.B"]);
        assert_eq!(layers.rgb().unwrap(), picture);
        assert_eq!(layers.rgb_layer("variance").unwrap(), variance);
        assert!(layers.rgb_layer("albedo").is_none());
    }
}
