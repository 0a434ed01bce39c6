//! Streaming a render to a running tev viewer over tev's TCP protocol (the `tev_client` crate:
//! CreateImage, then UpdateImage V3 with every channel): the image appears on the first pass
//! and is replaced after every pass, AOVs as extra channels, as pbrt-v4's `--display-server`
//! does. Nothing listening, or a connection lost on the way: one warning, and the render goes
//! on without a display.

use std::io::Write;
use std::net::{TcpStream, ToSocketAddrs};
use std::time::Duration;

use tev_client::{PacketCreateImage, PacketUpdateImage, TevClient};

use crate::film::{AovSet, Film};
use crate::render::RenderObserver;

/// Where tev listens unless told otherwise.
pub const DEFAULT_DISPLAY: &str = "127.0.0.1:14158";

/// How long to wait for tev to accept the connection.
const CONNECT_TIMEOUT: Duration = Duration::from_secs(1);

/// A render's image in tev, updated after every pass.
pub struct TevStream {
    address: String,
    name: String,
    aovs: AovSet,
    client: Option<TevClient>,
    created: bool,
}

fn warn(message: String) {
    // On stderr, beside the progress; a closed stderr does not stop the render.
    let _ = writeln!(std::io::stderr(), "warning: {message}");
}

impl TevStream {
    /// Connects to tev at `address` (`HOST:PORT`, or a port alone for 127.0.0.1) to show
    /// the image `name` with `aovs`; without tev there, warns and shows nothing.
    pub fn connect(address: &str, name: &str, aovs: AovSet) -> Self {
        let address = if address.parse::<u16>().is_ok() { format!("127.0.0.1:{address}") } else { address.to_string() };
        let socket = address
            .to_socket_addrs()
            .ok()
            .and_then(|mut a| a.next())
            .ok_or_else(|| "not a HOST:PORT address".to_string())
            .and_then(|a| TcpStream::connect_timeout(&a, CONNECT_TIMEOUT).map_err(|e| e.to_string()));
        let client = match socket {
            Ok(s) => Some(TevClient::wrap(s)),
            Err(e) => {
                warn(format!("no tev display at {address} ({e}); rendering without one (start tev first)"));
                None
            }
        };
        Self { address, name: name.to_string(), aovs, client, created: false }
    }

    /// Sends the film: the image on the first call, its pixels every time.
    fn send(&mut self, film: &Film) -> std::io::Result<()> {
        let Some(client) = self.client.as_mut() else { return Ok(()) };
        let layers = film.layers(self.aovs);
        let size = film.size();
        let names: Vec<&str> = layers.channels.iter().map(|c| c.name.as_str()).collect();
        if !self.created {
            client.send(PacketCreateImage {
                image_name: &self.name,
                grab_focus: true,
                width: size.x,
                height: size.y,
                channel_names: &names,
            })?;
            self.created = true;
        }
        // The channels one after another; channel k starts at k · pixels, stride 1.
        let pixels = size.x as u64 * size.y as u64;
        let offsets: Vec<u64> = (0..names.len() as u64).map(|k| k * pixels).collect();
        let data: Vec<f32> = layers.channels.iter().flat_map(|c| c.data.iter().copied()).collect();
        client.send(PacketUpdateImage {
            image_name: &self.name,
            grab_focus: false,
            channel_names: &names,
            channel_offsets: &offsets,
            channel_strides: &vec![1; names.len()],
            x: 0,
            y: 0,
            width: size.x,
            height: size.y,
            data: &data,
        })
    }
}

impl RenderObserver for TevStream {
    fn pass(&mut self, film: &Film, _elapsed: Duration) {
        if film.size().x == 0 || film.size().y == 0 {
            return;
        }
        if let Err(e) = self.send(film) {
            warn(format!("lost the tev display at {} ({e}); the render goes on without it", self.address));
            self.client = None;
        }
    }
}
