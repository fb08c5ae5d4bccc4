//! The window (winit) and what a hand does in it, turned into [`Action`]s. The event loop is *pumped*, not
//! run: the viewer asks for the window's events between batches of sensors and while it waits, so one
//! thread renders and presents, and a move is seen before the next batch.
//!
//! | hand | action |
//! |---|---|
//! | left drag | orbit about the target |
//! | right or middle drag | pan |
//! | wheel | dolly |
//! | `+` / `-`, `0` | exposure ± ½ stop, back to the start's |
//! | `1` … `5` | show the image, R, the sensors, the surfaces, the emission |
//! | `s` | save EXR + PNG |
//! | `r` | back to the scene's camera |
//! | `q`, Esc, closing the window | quit |

use std::time::{Duration, Instant};

use anyhow::{Context as _, Result, bail};
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::platform::pump_events::{EventLoopExtPumpEvents, PumpStatus};
use winit::window::{Window as WinitWindow, WindowAttributes, WindowId};

use super::display::Show;
use crate::vk::WindowTarget;

/// Degrees of orbit per pixel dragged.
const ORBIT_DEG_PER_PIXEL: f32 = 0.3;
/// Distance factor per wheel notch (up: closer).
const DOLLY_PER_NOTCH: f32 = 0.9;
/// Stops per exposure key.
const EXPOSURE_STEP: f32 = 0.5;
/// Said where no window opens.
const RENDER_HINT: &str = "; `sensorlight render SCENE -o out.exr` renders without one";
/// How long the window may take to appear.
const OPEN_TIMEOUT: Duration = Duration::from_secs(10);

/// What the viewer is asked to do.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    Orbit {
        yaw_deg: f32,
        pitch_deg: f32,
    },
    /// View heights at the target's distance.
    Pan {
        x: f32,
        y: f32,
    },
    Dolly(f32),
    /// Back to the scene's camera.
    ResetCamera,
    /// To the camera of this frame of the scene's camera path.
    Frame(u32),
    /// Play the camera path, a frame as each render is done; or stop playing.
    Play,
    ExposureBy(f32),
    ExposureTo(f32),
    /// Back to the exposure the viewer started with.
    ExposureReset,
    Show(Show),
    /// Save where `-o` says (`None`) or at the path.
    Save(Option<std::path::PathBuf>),
    /// Ask the window system for a window of this many pixels (a script's: a hand resizes by the frame).
    Resize(u32, u32),
    /// Show the picture again (the window was uncovered or resized).
    Redraw,
    Quit,
}

/// The viewer's window and its event loop.
pub struct Window {
    event_loop: EventLoop<()>,
    app: App,
}

struct App {
    attributes: WindowAttributes,
    window: Option<WinitWindow>,
    error: Option<anyhow::Error>,
    actions: Vec<Action>,
    /// The button held and where the cursor was last seen.
    drag: Option<MouseButton>,
    cursor: Option<PhysicalPosition<f64>>,
}

impl Window {
    /// Opens a window of `size` pixels titled `title`. Fails with the reason where no window can be opened.
    pub fn open(title: &str, size: (u32, u32)) -> Result<Self> {
        let event_loop = EventLoop::new().map_err(|e| anyhow::anyhow!("cannot open a window ({e}){RENDER_HINT}"))?;
        let attributes = WinitWindow::default_attributes()
            .with_title(title)
            .with_inner_size(PhysicalSize::new(size.0, size.1))
            .with_position(PhysicalPosition::new(0, 0));
        let app = App { attributes, window: None, error: None, actions: Vec::new(), drag: None, cursor: None };
        let mut window = Self { event_loop, app };
        let start = Instant::now();
        while window.app.window.is_none() {
            if let Some(e) = window.app.error.take() {
                return Err(e);
            }
            if start.elapsed() > OPEN_TIMEOUT {
                bail!("the window did not appear within {} s", OPEN_TIMEOUT.as_secs());
            }
            window.poll(Some(Duration::from_millis(10)));
        }
        Ok(window)
    }

    fn raw(&self) -> &WinitWindow {
        self.app.window.as_ref().expect("opened windows keep their window")
    }

    /// The window's handles, for a device to present to.
    pub fn target(&self) -> Result<WindowTarget> {
        let window = self.raw();
        let display = window.display_handle().context("the window's display handle")?.as_raw();
        let handle = window.window_handle().context("the window's handle")?.as_raw();
        Ok(WindowTarget { display, window: handle })
    }

    /// Its drawable size in pixels now.
    pub fn size(&self) -> (u32, u32) {
        let s = self.raw().inner_size();
        (s.width, s.height)
    }

    /// Asks for a drawable size of `size` pixels; the window system may grant another (a `Resized` follows).
    pub fn request_size(&self, size: (u32, u32)) {
        // Where it is granted at once, the size is reported by `size` without an event.
        let _ = self.raw().request_inner_size(PhysicalSize::new(size.0, size.1));
    }

    pub fn set_title(&self, title: &str) {
        self.raw().set_title(title);
    }

    /// What happened since the last call, waiting up to `wait` for something (`Some(ZERO)`: not at all).
    pub fn poll(&mut self, wait: Option<Duration>) -> Vec<Action> {
        if let PumpStatus::Exit(_) = self.event_loop.pump_app_events(wait, &mut self.app) {
            self.app.actions.push(Action::Quit);
        }
        std::mem::take(&mut self.app.actions)
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_none() && self.error.is_none() {
            match event_loop.create_window(self.attributes.clone()) {
                Ok(window) => self.window = Some(window),
                Err(e) => self.error = Some(anyhow::anyhow!("cannot open a window ({e}){RENDER_HINT}")),
            }
        }
    }

    fn window_event(&mut self, _: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested | WindowEvent::Destroyed => self.actions.push(Action::Quit),
            WindowEvent::Resized(_) | WindowEvent::RedrawRequested => self.actions.push(Action::Redraw),
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                self.actions.extend(key(event.logical_key.as_ref()));
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.drag = (state == ElementState::Pressed).then_some(button);
            }
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::CursorMoved { position, .. } => {
                let height = self.window.as_ref().map_or(1.0, |w| w.inner_size().height.max(1) as f32);
                if let (Some(button), Some(last)) = (self.drag, self.cursor) {
                    let (dx, dy) = ((position.x - last.x) as f32, (position.y - last.y) as f32);
                    self.actions.push(match button {
                        // The scene follows the hand: dragging right turns it right (the eye left).
                        MouseButton::Left => {
                            Action::Orbit { yaw_deg: -dx * ORBIT_DEG_PER_PIXEL, pitch_deg: dy * ORBIT_DEG_PER_PIXEL }
                        }
                        _ => Action::Pan { x: -dx / height, y: dy / height },
                    });
                }
                self.cursor = Some(position);
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.actions.push(Action::Dolly(DOLLY_PER_NOTCH.powf(notches)));
            }
            _ => {}
        }
    }
}

/// The action of a key, if any.
fn key(key: Key<&str>) -> Option<Action> {
    Some(match key {
        Key::Named(NamedKey::Escape) => Action::Quit,
        Key::Character(c) => match c {
            "q" | "Q" => Action::Quit,
            "+" | "=" => Action::ExposureBy(EXPOSURE_STEP),
            "-" | "_" => Action::ExposureBy(-EXPOSURE_STEP),
            "0" => Action::ExposureReset,
            "s" | "S" => Action::Save(None),
            "r" | "R" => Action::ResetCamera,
            "p" | "P" => Action::Play,
            other => Show::ALL.into_iter().find(|s| other.starts_with(s.key())).map(Action::Show)?,
        },
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_map_to_their_actions() {
        assert_eq!(key(Key::Named(NamedKey::Escape)), Some(Action::Quit));
        assert_eq!(key(Key::Character("+")), Some(Action::ExposureBy(EXPOSURE_STEP)));
        assert_eq!(key(Key::Character("3")), Some(Action::Show(Show::Sensors)));
        assert_eq!(key(Key::Character("s")), Some(Action::Save(None)));
        assert_eq!(key(Key::Character("x")), None);
        assert_eq!(key(Key::Named(NamedKey::Tab)), None);
    }
}
