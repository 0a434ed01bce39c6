//! `myriad view`: the progressive render in a window. Keys switch the light sampler (the
//! accumulation restarts), change the exposure, flip to the relative error against a
//! reference, save the image; the mouse orbits, pans and dollies the camera.
//!
//! Owns: the window (minifb: X11 through Xlib loaded at run time, 7 crates and 8 s to build,
//! against winit + softbuffer's 98 crates and 86 s) and its event loop. The render runs on a
//! thread of its own ([`worker`]): a half-size preview first, then ever longer passes, so the
//! first image comes at once; a new view calls off the pass under way at the next pixel. The
//! image at N spp is the one `myriad render --spp N` makes with the same seed, bit for bit. Closing the window, Esc,
//! Ctrl-C or SIGTERM end the view; a saved image is written whole or not at all.

mod controls;
mod screen;
mod worker;

use std::collections::VecDeque;
use std::fmt;
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::time::{Duration, Instant};

use std::cell::RefCell;
use std::rc::Rc;

use minifb::{InputCallback, Key, MouseButton, MouseMode, Window, WindowOptions};

use self::controls::{Action, Navigation};
use self::worker::{Accumulate, Frame, Order, Report, View};
use super::settings::{RenderRequest, Resolved};
use super::{SceneOptions, load_scene};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::film::AovSet;
use crate::interrupt::{self, Stop};
use crate::math::{Rgb, UVec2};
use crate::scene::BuildOptions;
use crate::settings::LightSamplerKind;

pub use self::controls::KEYS;

/// How far the view refines when no `--spp` or `--time` says: as good as unlimited.
pub const UNLIMITED_SPP: u32 = 1 << 24;

/// How often the window polls its events and redraws.
const FPS: usize = 60;

/// Everything `view` can be told.
#[derive(Clone, Debug, Default)]
pub struct ViewOptions {
    /// Scene file; `None` shows the built-in Cornell box.
    pub scene: Option<PathBuf>,
    /// Sampler, seed and depth; `spp` and `time` cap the refinement (unlimited otherwise).
    pub settings: RenderRequest,
    /// Image size.
    pub resolution: Option<UVec2>,
    /// Camera name.
    pub camera: Option<String>,
    /// How to read the scene file.
    pub load: crate::io::LoadOptions,
    /// Starting exposure, in stops.
    pub exposure: f32,
    /// Reference for the error view; `None` uses the one `myriad compare` cached for this
    /// scene in `compare-NAME/`, if any.
    pub reference: Option<PathBuf>,
    /// Where the save key writes its EXRs.
    pub out_dir: PathBuf,
    /// Close the window once the cap is reached (for scripts and benchmarks).
    pub exit_when_done: bool,
    /// Print nothing on the way (the summary is still returned).
    pub quiet: bool,
}

/// What a viewing session did, for the summary.
#[derive(Clone, Debug, Default)]
pub struct ViewReport {
    /// From the scene being built to the first image on screen.
    pub first_image: Option<Duration>,
    /// Accumulations started (the first, then one per sampler switch or camera move).
    pub views: u64,
    /// The last image shown: its sampler, spp and samples per second.
    pub last: Option<(LightSamplerKind, u32, f64)>,
    /// Images saved.
    pub saved: Vec<PathBuf>,
    /// Whether a signal (Ctrl-C, SIGTERM) ended the view.
    pub interrupted: bool,
}

impl fmt::Display for ViewReport {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        if let Some((sampler, spp, rate)) = self.last {
            write!(f, "view: last image {sampler} at {spp} spp, {}samples/s", super::human_rate(rate))?;
        } else {
            write!(f, "view: closed before the first image")?;
        }
        write!(f, "; {} view(s)", self.views)?;
        if let Some(t) = self.first_image {
            write!(f, "; first image {} after the scene was built", super::human_duration(t))?;
        }
        for path in &self.saved {
            write!(f, "\nsaved {}", path.display())?;
        }
        Ok(())
    }
}

/// Loads the scene, opens the window and runs it until closed.
pub fn view(opts: &ViewOptions) -> Result<ViewReport> {
    let scene_options = SceneOptions {
        load: opts.load,
        build: BuildOptions { resolution: opts.resolution, camera: opts.camera.clone(), ..Default::default() },
    };
    let mut loaded = load_scene(opts.scene.as_deref(), &scene_options)?;
    let built = Instant::now();
    let request =
        RenderRequest { spp: Some(opts.settings.spp.unwrap_or(UNLIMITED_SPP)), time: None, ..opts.settings.clone() };
    let resolved = request.resolve(&loaded.report.render, UNLIMITED_SPP)?;
    let size = loaded.report.resolution;
    let reference = reference(opts, size)?;
    let plan = Accumulate {
        settings: resolved.render_settings(size, AovSet::default()),
        spp: resolved.budget.fixed().map_or(UNLIMITED_SPP, |f| f.1),
        time: opts.settings.time,
        scene_name: loaded.report.source.clone(),
        tracer: loaded.report.stats.tracer,
    };
    crate::io::ensure_dir(&opts.out_dir)?;
    let title = format!("myriad view: {}", loaded.report.source);

    let scene = &mut loaded.scene;
    let navigation = Navigation::new(scene.camera, scene.center, scene.radius, size.y);
    let _busy = interrupt::busy();
    let cancel = AtomicBool::new(false);
    let (orders, their_orders) = mpsc::channel();
    let (their_reports, reports) = mpsc::channel();
    let mut ui = Ui::new(opts, size, &resolved, navigation, reference, built, &cancel);
    // The first pass renders while the window opens.
    std::thread::scope(|s| {
        s.spawn(|| worker::run(scene, &plan, &cancel, their_orders, their_reports));
        ui.restart(&orders);
        let result = open_window(&title, size).and_then(|window| ui.run(window, &orders, &reports));
        cancel.store(true, Ordering::Relaxed);
        let _ = orders.send(Order::Quit);
        result
    })?;
    Ok(ui.report)
}

/// The reference for the error view: the one given (which must fit), else `compare`'s cached
/// one for this scene when it has the view's size.
fn reference(opts: &ViewOptions, size: UVec2) -> Result<Option<(PathBuf, Vec<Rgb>)>> {
    if let Some(path) = &opts.reference {
        return Ok(Some((path.clone(), super::compare::read_reference(path, size)?.pixels)));
    }
    let cached = super::compare::default_out_dir(opts.scene.as_deref()).join("reference.exr");
    Ok(super::compare::read_reference(&cached, size).ok().map(|r| (cached, r.pixels)))
}

/// A window for a `size` image and the status bar, or an error saying what to do instead.
fn open_window(title: &str, size: UVec2) -> Result<Window> {
    let height = size.y + screen::bar_height(size.x, &KEYS);
    let mut window = Window::new(title, size.x as usize, height as usize, WindowOptions::default()).map_err(|e| {
        Error::Usage(format!(
            "cannot open a window ({e}); `myriad view` needs a display (is DISPLAY set?). \
             Without one, render with `myriad render`, or stream to tev with `--display`"
        ))
    })?;
    window.set_target_fps(FPS);
    on_lost_display();
    Ok(window)
}

/// A lost X display (server gone, connection cut) ends the process: Xlib exits after its
/// handler returns whatever the handler does. Ours says so in words instead of Xlib's; a
/// saved image is whole either way (written to a temporary file, then renamed).
#[cfg(target_os = "linux")]
fn on_lost_display() {
    unsafe extern "C" fn lost(_: *mut x11_dl::xlib::Display) -> std::os::raw::c_int {
        let _ = writeln!(std::io::stderr(), "error: lost the display; the view ends (images saved so far are whole)");
        std::process::exit(1)
    }
    if let Ok(xlib) = x11_dl::xlib::Xlib::open() {
        // SAFETY: sets a process-wide callback; the handler only writes to stderr and exits.
        unsafe { (xlib.XSetIOErrorHandler)(Some(lost)) };
    }
}

#[cfg(not(target_os = "linux"))]
fn on_lost_display() {}

/// Every key press as it comes (minifb's per-frame key state misses a press and release that
/// fall between two frames, as a quick tap or a scripted key does).
#[derive(Clone, Default)]
struct KeyPresses(Rc<RefCell<Vec<Key>>>);

impl InputCallback for KeyPresses {
    fn add_char(&mut self, _: u32) {}
    fn set_key_state(&mut self, key: Key, down: bool) {
        if down {
            self.0.borrow_mut().push(key);
        }
    }
}

/// The window's side: what is shown and how, and what the user did.
struct Ui<'a> {
    opts: &'a ViewOptions,
    size: UVec2,
    exposure: f32,
    show_error: bool,
    sampler: LightSamplerKind,
    /// Whether paths are guided.
    guiding: bool,
    /// Whether light through smooth glass is solved for.
    caustics: bool,
    camera: Camera,
    navigation: Navigation,
    reference: Option<(PathBuf, Vec<Rgb>)>,
    generation: u64,
    frame: Option<Frame>,
    /// When the frames of the current view arrived (for frames per second).
    arrivals: VecDeque<Instant>,
    /// The last thing worth saying (saved, failed, no reference).
    message: String,
    built: Instant,
    announced_done: bool,
    report: ViewReport,
    /// Set before a new view is sent: the render thread calls off the pass under way.
    cancel: &'a AtomicBool,
}

impl<'a> Ui<'a> {
    fn new(
        opts: &'a ViewOptions,
        size: UVec2,
        resolved: &Resolved,
        navigation: Navigation,
        reference: Option<(PathBuf, Vec<Rgb>)>,
        built: Instant,
        cancel: &'a AtomicBool,
    ) -> Self {
        let message = match &reference {
            Some((path, _)) => format!("reference {}", path.display()),
            None => "no reference (--reference, or run compare first)".into(),
        };
        Self {
            opts,
            size,
            exposure: opts.exposure,
            show_error: false,
            sampler: resolved.sampler,
            guiding: resolved.guiding,
            caustics: resolved.caustics,
            camera: navigation.home,
            navigation,
            reference,
            generation: 0,
            frame: None,
            arrivals: VecDeque::new(),
            message,
            built,
            announced_done: false,
            report: ViewReport::default(),
            cancel,
        }
    }

    /// Polls the window until it is closed, Esc or a signal, or (with `exit_when_done`) the
    /// accumulation is done; asks the render thread for every new view after the first.
    fn run(&mut self, mut window: Window, orders: &Sender<Order>, reports: &Receiver<Report>) -> Result<()> {
        let mut last_mouse: Option<(f32, f32)> = None;
        let mut buffer = Vec::new();
        let presses = KeyPresses::default();
        window.set_input_callback(Box::new(presses.clone()));
        while window.is_open() {
            if interrupt::requested() != Stop::No {
                self.report.interrupted = true;
                break;
            }
            let mut redraw = buffer.is_empty();
            for key in presses.0.take() {
                match controls::action(key) {
                    Some(Action::Quit) => return Ok(()),
                    Some(action) => redraw |= self.act(action, orders),
                    None => {}
                }
            }
            if self.navigate(&window, &mut last_mouse) {
                self.restart(orders);
            }
            redraw |= self.receive(reports);
            if redraw {
                buffer = self.compose();
                window
                    .update_with_buffer(
                        &buffer,
                        self.size.x as usize,
                        (self.size.y + screen::bar_height(self.size.x, &KEYS)) as usize,
                    )
                    .map_err(|e| Error::Usage(format!("the window failed: {e}")))?;
                self.shown();
            } else {
                window.update();
            }
            if self.opts.exit_when_done
                && self.frame.as_ref().is_some_and(|f| f.done && f.generation == self.generation)
            {
                break;
            }
        }
        Ok(())
    }

    /// Does what a key asks; whether the picture changes.
    fn act(&mut self, action: Action, orders: &Sender<Order>) -> bool {
        match action {
            Action::Sampler(s) => {
                self.sampler = s;
                self.restart(orders);
            }
            Action::ToggleGuiding => {
                self.guiding = !self.guiding;
                self.restart(orders);
            }
            Action::ToggleCaustics => {
                self.caustics = !self.caustics;
                self.restart(orders);
            }
            Action::Exposure(stops) => self.exposure += stops,
            Action::ToggleError if self.reference.is_some() => self.show_error = !self.show_error,
            Action::ToggleError => self.message = "no reference to show the error against: pass --reference".into(),
            Action::Save => {
                let _ = orders.send(Order::Save(self.opts.out_dir.clone()));
            }
            Action::ResetCamera => {
                self.camera = self.navigation.reset();
                self.restart(orders);
            }
            Action::Quit => {}
        }
        true
    }

    /// Moves the camera as the mouse drags or the wheel turns; whether it moved.
    fn navigate(&mut self, window: &Window, last: &mut Option<(f32, f32)>) -> bool {
        let (left, right) = (window.get_mouse_down(MouseButton::Left), window.get_mouse_down(MouseButton::Right));
        let shift = window.is_key_down(Key::LeftShift) || window.is_key_down(Key::RightShift);
        let pos = window.get_mouse_pos(MouseMode::Pass).filter(|_| left || right);
        let mut moved = false;
        if let (Some((x, y)), Some((x0, y0))) = (pos, *last)
            && (x, y) != (x0, y0)
        {
            let (dx, dy) = (x - x0, y - y0);
            self.camera = if right || shift {
                self.navigation.pan(&self.camera, dx, dy)
            } else {
                self.navigation.orbit(&self.camera, dx, dy)
            };
            moved = true;
        }
        *last = pos;
        if let Some((_, notches)) = window.get_scroll_wheel().filter(|w| w.1 != 0.0) {
            self.camera = self.navigation.dolly(&self.camera, notches);
            moved = true;
        }
        moved
    }

    /// Asks for the current sampler and camera from sample 0.
    fn restart(&mut self, orders: &Sender<Order>) {
        self.generation += 1;
        self.report.views += 1;
        self.arrivals.clear();
        self.announced_done = false;
        self.cancel.store(true, Ordering::Relaxed);
        let _ = orders.send(Order::Show(View {
            generation: self.generation,
            sampler: self.sampler,
            guiding: self.guiding,
            caustics: self.caustics,
            camera: self.camera,
        }));
    }

    /// Takes what the render thread said; whether there is something new to show.
    fn receive(&mut self, reports: &Receiver<Report>) -> bool {
        let mut fresh = false;
        while let Ok(report) = reports.try_recv() {
            match report {
                Report::Frame(frame) if frame.generation == self.generation => {
                    self.arrivals.push_back(Instant::now());
                    self.frame = Some(frame);
                }
                Report::Frame(_) => continue,
                Report::Saved(path) => {
                    self.message = format!("saved {}", path.display());
                    self.say(&self.message);
                    self.report.saved.push(path);
                }
                Report::Failed(why) => {
                    self.message = format!("failed: {why}");
                    self.say(&self.message);
                }
            }
            fresh = true;
        }
        fresh
    }

    /// The window's pixels now.
    fn compose(&mut self) -> Vec<u32> {
        let now = Instant::now();
        while self.arrivals.front().is_some_and(|&t| now - t > Duration::from_secs(1)) {
            self.arrivals.pop_front();
        }
        let Some(frame) = &self.frame else {
            let black = vec![Rgb::ZERO; (self.size.x * self.size.y) as usize];
            let status = [format!("{}: rendering...", self.sampler)];
            return screen::compose(self.size, &black, 0.0, None, &status, &KEYS);
        };
        let error = self.reference.as_ref().filter(|_| self.show_error).map(|r| r.1.as_slice());
        let spp = match (frame.spp, frame.done) {
            (0, _) => "preview".to_string(),
            (n, true) => format!("{n} spp (done)"),
            (n, false) => format!("{n} spp"),
        };
        let status = [
            frame.label.clone(),
            spp,
            format!("{}samples/s", super::human_rate(frame.samples_per_second)),
            format!("{} frames/s", self.arrivals.len()),
            if error.is_some() { "relative error".to_string() } else { format!("exposure {:+.1}", self.exposure) },
            self.message.clone(),
        ];
        screen::compose(self.size, &frame.pixels, self.exposure, error, &status, &KEYS)
    }

    /// Notes what the window now shows: the first image, an accumulation done.
    fn shown(&mut self) {
        let Some(frame) = &self.frame else { return };
        self.report.first_image.get_or_insert_with(|| self.built.elapsed());
        self.report.last = Some((frame.sampler, frame.spp, frame.samples_per_second));
        if frame.done && frame.generation == self.generation && !self.announced_done {
            self.announced_done = true;
            let line = format!("view: showing {} at {} spp (done)", frame.sampler, frame.spp);
            self.say(&line);
        }
    }

    /// A line on stderr, unless quiet.
    fn say(&self, line: &str) {
        if !self.opts.quiet {
            let _ = writeln!(std::io::stderr(), "{line}");
        }
    }
}
