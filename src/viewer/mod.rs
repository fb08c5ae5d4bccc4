//! `sensorlight view`: a window that shows a render converging, round by round, and starts it again when
//! the camera moves (docs/DESIGN.md §12). It drives the same [`Renderer`] as `render`, through its
//! [`Progress`]: each round's snapshot is presented as it lands, and before each batch of sensors the
//! window's events are read, so a move stops the render in progress (the batches in flight are waited for)
//! and starts the next from the new camera. The radiance cache does not depend on the camera and is solved
//! once. One thread does everything; presenting has its own command slot and never waits for sensor
//! batches.
//!
//! ```text
//!   window events ─► actions ─► camera moved? ─► render(camera) ─┬─ snapshot after each round ─► present
//!        ▲                                                       ├─ before each batch: events (a move stops it)
//!        └───────────────────────────────────────────────────────┴─ done: present the image (or an AOV)
//! ```

pub mod display;
pub mod orbit;
mod present;
mod progress;
pub mod script;
mod window;

use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Result;
use glam::Vec4;

pub use display::Show;
use orbit::Orbit;
use present::Presenter;
use progress::ViewProgress;
use script::{Command, ScriptRun};
pub use window::Action;
use window::Window;

use crate::cancel::{Cancelled, Reason};
use crate::params::FrameParams;
use crate::renderer::{Phase, RenderOutput, Renderer};
use crate::scene::{Aabb, Camera, CameraPath, ImageSize, Scene};
use crate::vk::{Device, WindowTarget};

/// How long the viewer waits for an event when it has nothing to render.
const IDLE_WAIT: Duration = Duration::from_millis(50);
/// The title is rewritten at most this often while rendering.
const TITLE_EVERY: Duration = Duration::from_millis(250);

/// What the viewer shows and how.
pub struct ViewSetup<'a> {
    pub scene: &'a Scene,
    pub size: ImageSize,
    pub frame: FrameParams,
    /// Stops, as `render`'s PNG.
    pub exposure: f32,
    /// The scene's name in the title.
    pub name: String,
    /// Where `s` saves (an `.exr`; its PNG beside it).
    pub output: PathBuf,
    /// Commands to run instead of (beside) a hand's.
    pub script: Option<Vec<Command>>,
    /// Say each move's time to its first picture, and a summary at the end.
    pub timings: bool,
}

/// What the viewer needs of its caller (the command line): the device, the renderer, the files, the voice.
pub trait ViewHost {
    /// Opens a device that presents to `window`.
    fn open(&mut self, window: WindowTarget) -> Result<Arc<Device>>;
    /// Builds the renderer on it, as `render` would.
    fn build(&mut self, device: &Arc<Device>, scene: &Scene) -> Result<Renderer>;
    /// The exposure `render` would give `output`'s PNG where it chooses one itself (a bare mesh's), if so.
    fn exposure(&self, output: &RenderOutput) -> Option<f32>;
    /// Writes `output`, rendered from `camera`, at `path` as `render -o path --aovs` would (all files or
    /// none); the files written.
    fn save(&mut self, output: &RenderOutput, camera: &Camera, exposure: f32, path: &Path) -> Result<Vec<PathBuf>>;
    /// Says a line to the user (on standard error, unless quiet).
    fn say(&self, line: &str);
    /// Whether a signal asked the viewer to stop.
    fn interrupted(&self) -> Option<Reason>;
}

/// Opens the window and shows `setup.scene` until the window is closed (or the script quits).
pub fn run(setup: ViewSetup<'_>, host: &mut dyn ViewHost) -> Result<()> {
    let size = setup.size;
    let window = Window::open(&format!("sensorlight · {}", setup.name), (size.width, size.height))?;
    let device = host.open(window.target()?)?;
    let presenter = Presenter::new(&device, size, window.size())?;
    let mut renderer = host.build(&device, setup.scene)?;
    renderer.keep_cache();
    let orbit = Orbit::new(&setup.scene.camera, &setup.scene.mesh.bounds);
    let mut session = Session {
        window,
        presenter,
        host,
        camera: setup.scene.camera,
        scene_camera: setup.scene.camera,
        start: orbit,
        orbit,
        exposure: setup.exposure,
        start_exposure: setup.exposure,
        exposure_chosen: false,
        show: Show::Image,
        name: setup.name.clone(),
        output_path: setup.output.clone(),
        script: setup.script.clone().map(|commands| ScriptRun { commands, next: 0, syncs: 0, resizing: None }),
        timings: setup.timings,
        wanted: true,
        quit: false,
        error: None,
        saves: Vec::new(),
        this: RenderState::new(),
        moved_at: None,
        first_images: Vec::new(),
        last_title: Instant::now(),
        path: setup.scene.camera_path.clone(),
        playing: None,
        bounds: setup.scene.mesh.bounds,
    };
    let result = session.run(&mut renderer, &setup);
    let summary = session.summary();
    // Everything made on the device goes before it (each waits for its own work), and the device, which
    // owns the window's surface, before the window.
    let Session { window, presenter, .. } = session;
    drop((renderer, presenter));
    drop(device);
    drop(window);
    if let Some(line) = summary {
        host.say(&line);
    }
    result
}

/// One render's progress as the window shows it.
struct RenderState {
    started: Instant,
    phase: Phase,
    sensors: u64,
    /// Rounds presented.
    rounds: u32,
    resolved: f64,
    bounce: u32,
    /// The last snapshot's image.
    preview: Option<Vec<Vec4>>,
    /// The finished render.
    output: Option<RenderOutput>,
}

impl RenderState {
    fn new() -> Self {
        let started = Instant::now();
        Self {
            started,
            phase: Phase::GBuffer,
            sensors: 0,
            rounds: 0,
            resolved: 0.0,
            bounce: 0,
            preview: None,
            output: None,
        }
    }

    fn done(&self) -> bool {
        self.output.is_some()
    }
}

struct Session<'h> {
    window: Window,
    presenter: Presenter,
    host: &'h mut dyn ViewHost,
    camera: Camera,
    orbit: Orbit,
    /// The scene's own camera, for `r` (an orbit's camera reproduces it only to rounding).
    scene_camera: Camera,
    start: Orbit,
    exposure: f32,
    start_exposure: f32,
    /// Whether the host was asked for its exposure (after the first render).
    exposure_chosen: bool,
    show: Show,
    name: String,
    output_path: PathBuf,
    script: Option<ScriptRun>,
    timings: bool,
    /// A render from `camera` is wanted (none yet, or the camera moved).
    wanted: bool,
    quit: bool,
    /// An error met inside a progress callback, returned once the render has stopped.
    error: Option<anyhow::Error>,
    /// Saves asked for, done once the render is (a path, or `None` for `-o`'s), with whether a failure ends
    /// the viewer (a script's) or is only said (a key's).
    saves: Vec<(Option<PathBuf>, bool)>,
    this: RenderState,
    /// When the camera last moved, until the first picture from it is shown.
    moved_at: Option<Instant>,
    first_images: Vec<Duration>,
    last_title: Instant,
    /// The scene's camera path (`p` plays it, a script's `frame K` goes to a frame), and the frame shown
    /// while it plays.
    path: Option<CameraPath>,
    playing: Option<u32>,
    bounds: Aabb,
}

impl Session<'_> {
    fn run(&mut self, renderer: &mut Renderer, setup: &ViewSetup<'_>) -> Result<()> {
        loop {
            if let Some(reason) = self.host.interrupted() {
                return Err(Cancelled(reason).into());
            }
            let wait = if self.wanted { Some(Duration::ZERO) } else { Some(IDLE_WAIT) };
            self.pump(wait);
            if let Some(e) = self.error.take() {
                return Err(e);
            }
            if self.quit {
                return Ok(());
            }
            if !self.wanted {
                continue;
            }
            self.wanted = false;
            self.this = RenderState::new();
            renderer.set_camera(self.camera);
            let result = renderer.render(setup.size, &setup.frame, &ViewProgress(RefCell::new(&mut *self)));
            match result {
                Ok(output) => {
                    // A bare mesh's automatic exposure, once, as `render` would choose it, unless already set by hand.
                    if let (false, Some(stops)) = (self.exposure_chosen, self.host.exposure(&output)) {
                        if self.exposure == self.start_exposure {
                            self.exposure = stops;
                        }
                        self.start_exposure = stops;
                    }
                    self.exposure_chosen = true;
                    self.this.output = Some(output);
                    self.title(true);
                    self.present();
                    self.run_saves();
                    // Playing the path: the next frame (from the first again after the last).
                    if let (Some(k), Some(path)) = (self.playing, &self.path) {
                        let next = if k >= path.last_frame() { 0 } else { k + 1 };
                        self.playing = Some(next);
                        self.apply(Action::Frame(next));
                    }
                }
                Err(e) if matches!(e.downcast_ref::<Cancelled>(), Some(Cancelled(Reason::Superseded))) => {}
                Err(e) => return Err(e),
            }
        }
    }

    /// Reads the window's events and the script's next commands, and does what they ask.
    fn pump(&mut self, wait: Option<Duration>) {
        // The window's first, so that a script that goes on (and may block in `sync`) sees their effect.
        let from_window = self.window.poll(wait);
        self.act(from_window);
        let from_script = self.step_script();
        self.act(from_script);
    }

    fn act(&mut self, actions: Vec<Action>) {
        let mut redraw = false;
        for action in actions {
            redraw |= self.apply(action);
        }
        if redraw {
            self.present();
        }
        if self.this.done() {
            self.run_saves();
        }
    }

    /// Does `action`; whether the picture must be shown again.
    fn apply(&mut self, action: Action) -> bool {
        let before = self.orbit;
        match action {
            Action::Orbit { yaw_deg, pitch_deg } => self.orbit.orbit(yaw_deg, pitch_deg),
            Action::Pan { x, y } => self.orbit.pan(x, y),
            Action::Dolly(f) => self.orbit.dolly(f),
            Action::ResetCamera => self.orbit = self.start,
            Action::Frame(k) => return self.go_to_frame(k),
            Action::Play => {
                self.playing = match self.playing {
                    Some(_) => None,
                    None if self.path.is_some() => Some(0),
                    None => {
                        self.host.say("no camera path to play: the scene file has no [path]");
                        None
                    }
                };
                return self.playing.is_some_and(|k| self.go_to_frame(k));
            }
            Action::ExposureBy(stops) => self.exposure += stops,
            Action::ExposureTo(stops) => self.exposure = stops,
            Action::ExposureReset => self.exposure = self.start_exposure,
            Action::Show(show) => self.show = show,
            Action::Save(path) => {
                // The picture shown when the save is asked: at once where the render is done (a move that
                // follows in the same batch of actions starts another), else once it is.
                let fatal = path.is_some();
                self.saves.push((path, fatal));
                if self.this.done() {
                    self.run_saves();
                }
                return false;
            }
            Action::Resize(width, height) => self.window.request_size((width, height)),
            Action::Redraw => {}
            Action::Quit => {
                self.quit = true;
                return false;
            }
        }
        if self.orbit != before {
            // The scene's own camera where `r` went back to it, so that it renders as the file says.
            let camera = if self.orbit == self.start { Ok(self.scene_camera) } else { self.orbit.camera() };
            match camera {
                Ok(camera) => {
                    self.camera = camera;
                    self.wanted = true;
                    // Waits in a script (`wait done`) are for the render from here.
                    self.this = RenderState::new();
                    self.moved_at = Some(Instant::now());
                }
                Err(_) => self.orbit = before,
            }
            return false;
        }
        self.title(true);
        true
    }

    /// Looks from frame `k` of the camera path, exactly as `render --frame K` does; an orbit goes on from
    /// there. Says why where there is no such frame.
    fn go_to_frame(&mut self, k: u32) -> bool {
        let Some(path) = &self.path else {
            self.host.say(&format!("no frame {k}: the scene file has no camera path ([path])"));
            return false;
        };
        if k > path.last_frame() {
            self.host.say(&format!("no frame {k}: the path's last is frame {}", path.last_frame()));
            return false;
        }
        match path.camera(k) {
            Ok(camera) => {
                self.camera = camera;
                self.orbit = Orbit::new(&camera, &self.bounds);
                self.wanted = true;
                self.this = RenderState::new();
                self.moved_at = Some(Instant::now());
            }
            Err(e) => self.host.say(&format!("{e:#}")),
        }
        false
    }

    /// Shows what [`Session::show`] says of the render so far.
    fn present(&mut self) {
        let rgb = match (&self.this.output, &self.this.preview) {
            (Some(output), _) => display::picture(self.show, output, self.exposure),
            (None, Some(preview)) => display::preview(preview, self.exposure),
            (None, None) => return,
        };
        let texels = display::texels(&rgb, self.presenter.format());
        if let Err(e) = self.presenter.show(&texels, self.window.size()) {
            self.error.get_or_insert(e);
        }
        if let Some(moved) = self.moved_at.take() {
            let t = moved.elapsed();
            self.first_images.push(t);
            if self.timings {
                self.host.say(&format!("first picture {:.3} s after the move", t.as_secs_f64()));
            }
        }
    }

    /// Writes the saves asked for (the render is done).
    fn run_saves(&mut self) {
        let Some(output) = &self.this.output else { return };
        for (path, fatal) in std::mem::take(&mut self.saves) {
            let path = path.unwrap_or_else(|| self.output_path.clone());
            match self.host.save(output, &self.camera, self.exposure, &path) {
                Ok(files) => {
                    let names: Vec<String> = files.iter().map(|p| p.display().to_string()).collect();
                    self.host.say(&format!("wrote {}", names.join(", ")));
                }
                Err(e) if fatal => {
                    self.error.get_or_insert(e);
                }
                Err(e) => self.host.say(&format!("error: cannot save {}: {e:#}", path.display())),
            }
        }
    }

    /// Writes the window's title (at most every [`TITLE_EVERY`] unless `now`).
    fn title(&mut self, now: bool) {
        if !now && self.last_title.elapsed() < TITLE_EVERY {
            return;
        }
        self.last_title = Instant::now();
        let s = &self.this;
        let seconds = s.started.elapsed().as_secs_f64();
        let state = match (&s.output, s.phase) {
            (Some(out), _) => {
                let what = match self.show {
                    Show::Image => String::new(),
                    show => format!(" · {}", show.word()),
                };
                format!("done in {:.1} s · {} sensors{what}", out.stats.total_seconds, out.stats.sensors)
            }
            (None, Phase::Bounces) => format!("global illumination: bounce {} · {} sensors", s.bounce + 1, s.sensors),
            (None, Phase::GBuffer) => "starting".into(),
            (None, _) => format!(
                "round {} · {:.0} % resolved · {:.0} sensors/s",
                s.rounds.max(1),
                100.0 * s.resolved,
                s.sensors as f64 / seconds.max(1e-3)
            ),
        };
        let exposure = format!("exposure {:+.1}", self.exposure);
        self.window.set_title(&format!("sensorlight · {} · {state} · {exposure}", self.name));
    }

    /// The moves' times to their first picture, when asked for.
    fn summary(&self) -> Option<String> {
        if !self.timings || self.first_images.is_empty() {
            return None;
        }
        let mut t: Vec<f64> = self.first_images.iter().map(Duration::as_secs_f64).collect();
        t.sort_by(f64::total_cmp);
        Some(format!(
            "first picture after a move: median {:.3} s, slowest {:.3} s, over {} move(s)",
            t[t.len() / 2],
            t[t.len() - 1],
            t.len()
        ))
    }
}
