//! `sensorlight view` on a virtual display (Xvfb, installed by scripts/setup.sh): the window shows the very
//! pixels `render` writes for the same camera, a scripted orbit moves the camera as it says and the window
//! shows the render from there; without a display the viewer says so and fails.

mod common;

use std::io::{BufRead as _, BufReader, Read as _, Write as _};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use glam::{Quat, Vec3};

/// Small, so that each render takes seconds under the validation layer.
const SIZE: u32 = 64;
/// The orbit the script makes, degrees about the world's up.
const YAW_DEG: f32 = 20.0;

/// An X server of its own on a free display number, ended when dropped.
struct Xvfb {
    display: String,
    process: Child,
}

impl Xvfb {
    /// Xvfb picks the number itself (`-displayfd`) and writes it once it accepts connections: it passes over
    /// numbers in use and clears lock files left by servers that died, which tests running in separate
    /// processes (nextest) could not agree on among themselves.
    fn start() -> Self {
        let mut process = Command::new("Xvfb")
            .args(["-displayfd", "1", "-screen", "0", "320x240x24", "-nolisten", "tcp"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("the viewer's tests need Xvfb: run scripts/setup.sh (apt package xvfb)");
        let mut number = String::new();
        BufReader::new(process.stdout.take().unwrap()).read_line(&mut number).unwrap();
        let number = number.trim();
        assert!(!number.is_empty() && number.bytes().all(|b| b.is_ascii_digit()), "Xvfb did not start: {number:?}");
        Self { display: format!(":{number}"), process }
    }

    /// `sensorlight view` of the Cornell box at `size` × `size`, driven by `script`, on this display.
    fn view(&self, size: u32, script: &Path) -> Command {
        let size = size.to_string();
        let mut command = common::command();
        command
            .args(["view", "scenes/cornell/cornell.toml", "--width", &size, "--height", &size, "--script"])
            .arg(script)
            .env("DISPLAY", &self.display)
            .env_remove("WAYLAND_DISPLAY");
        command
    }

    /// The screen's top-left `SIZE` × `SIZE` pixels as RGB bytes.
    fn top_left(&self) -> Vec<u8> {
        self.pixels(SIZE, SIZE)
    }

    /// The screen's top-left `w` × `h` pixels as RGB bytes (xwd's dump, parsed).
    fn pixels(&self, w: u32, h: u32) -> Vec<u8> {
        let run = Command::new("xwd")
            .args(["-root", "-silent", "-display", &self.display])
            .output()
            .expect("the viewer's tests need xwd: run scripts/setup.sh (apt package x11-apps)");
        assert!(run.status.success(), "xwd: {}", String::from_utf8_lossy(&run.stderr));
        xwd_rgb(&run.stdout, w, h)
    }
}

impl Drop for Xvfb {
    /// SIGTERM, so that the server removes its lock file and socket (a SIGKILL leaves them behind).
    fn drop(&mut self) {
        let terminated = Command::new("kill").args(["-TERM", &self.process.id().to_string()]).status();
        if !terminated.is_ok_and(|s| s.success()) {
            let _ = self.process.kill();
        }
        let _ = self.process.wait();
    }
}

/// The top-left `w` × `h` pixels of an XWD dump (X11's window dump: a big-endian header, a colour map, then
/// the pixels) of a 24/32-bit true-colour screen, as RGB bytes.
fn xwd_rgb(dump: &[u8], w: u32, h: u32) -> Vec<u8> {
    let word = |i: usize| u32::from_be_bytes(dump[4 * i..4 * i + 4].try_into().unwrap());
    let (header, format, width, height) = (word(0) as usize, word(2), word(4), word(5));
    let (byte_order, bits, stride) = (word(7), word(11), word(12) as usize);
    let masks = [word(14), word(15), word(16)];
    let colours = word(19) as usize;
    assert_eq!((format, bits), (2, 32), "expected a 32-bit ZPixmap dump");
    assert!(width >= w && height >= h);
    let data = &dump[header + 12 * colours..];
    let mut rgb = Vec::with_capacity((3 * w * h) as usize);
    for y in 0..h as usize {
        for x in 0..w as usize {
            let b: [u8; 4] = data[y * stride + 4 * x..][..4].try_into().unwrap();
            let v = if byte_order == 0 { u32::from_le_bytes(b) } else { u32::from_be_bytes(b) };
            rgb.extend(masks.map(|m| ((v & m) >> m.trailing_zeros()) as u8));
        }
    }
    rgb
}

fn png_rgb(path: &Path) -> Vec<u8> {
    let decoder = png::Decoder::new(BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height, info.color_type), (SIZE, SIZE, png::ColorType::Rgb));
    buf.truncate(info.buffer_size());
    buf
}

/// How many bytes differ, and by at most how much.
fn difference(a: &[u8], b: &[u8]) -> (usize, u8) {
    let differ = a.iter().zip(b).filter(|(x, y)| x != y).count();
    (differ, a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0))
}

/// Screenshots until the window shows `expected` (presenting may land a moment after the viewer says it
/// did), for up to 10 s; the last screenshot.
fn screenshot_until(x: &Xvfb, expected: &[u8]) -> Vec<u8> {
    let start = Instant::now();
    loop {
        let shot = x.top_left();
        if shot == expected || start.elapsed() > Duration::from_secs(10) {
            return shot;
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// `render`'s PNG of `scene` at the test's size.
fn render_png(scene: &Path, out: &Path) -> Vec<u8> {
    let size = SIZE.to_string();
    let args = ["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--width", &size, "--height", &size];
    let run = common::sensorlight(&args);
    assert!(run.status.success(), "{}", common::stderr(&run));
    png_rgb(&out.with_extension("png"))
}

/// The camera a `sync` line reports.
#[derive(serde::Deserialize)]
struct Synced {
    eye: [f32; 3],
    target: [f32; 3],
    up: [f32; 3],
    vfov_deg: f32,
}

fn synced(line: &str, n: u32) -> Synced {
    let json = line.strip_prefix(&format!("sync {n} ")).unwrap_or_else(|| panic!("expected sync {n}, got {line}"));
    serde_json::from_str(json).unwrap()
}

#[test]
fn the_window_shows_what_render_writes_before_and_after_a_scripted_orbit() {
    let dir = common::scratch("viewer");
    let x = Xvfb::start();
    let script = dir.join("orbit.script");
    let saved = dir.join("saved.exr");
    std::fs::write(
        &script,
        format!("wait done\nsync\norbit {YAW_DEG} 0\nwait round 1\nwait done\nsync\nsave {}\nquit\n", saved.display()),
    )
    .unwrap();
    let mut viewer = x
        .view(SIZE, &script)
        .arg("--timings")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = viewer.stderr.take().unwrap();
    let errors = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = stderr.read_to_string(&mut text);
        text
    });
    let mut stdin = viewer.stdin.take().unwrap();
    let mut lines = BufReader::new(viewer.stdout.take().unwrap()).lines();
    let mut next_line = || lines.next().and_then(Result::ok).unwrap_or_default();

    // The scene's own camera: the window shows render's PNG, byte for byte.
    let first = next_line();
    let start = synced(&first, 1);
    let expected = render_png(&common::project("scenes/cornell/cornell.toml"), &dir.join("render.exr"));
    let shot = screenshot_until(&x, &expected);
    let (differ, most) = difference(&shot, &expected);
    assert!(differ == 0, "the window differs from render's PNG in {differ} bytes, by up to {most}");
    writeln!(stdin).unwrap();

    // After `orbit 20 0`: the eye turned 20° about the up through the target, nothing else moved.
    let second = next_line();
    let moved = synced(&second, 2);
    let (eye0, target) = (Vec3::from(start.eye), Vec3::from(start.target));
    let eye = target + Quat::from_axis_angle(Vec3::from(start.up), YAW_DEG.to_radians()) * (eye0 - target);
    assert!((Vec3::from(moved.eye) - eye).length() < 1e-3 * (eye0 - target).length(), "{second}");
    assert_eq!((moved.target, moved.up, moved.vfov_deg), (start.target, start.up, start.vfov_deg));
    // That camera written into a scene file and rendered: the window shows it, and it is another image.
    let obj = common::project("scenes/cornell/cornell.obj");
    let f = |v: [f32; 3]| format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2]);
    let toml = format!(
        "mesh = {:?}\n[camera]\neye = {}\ntarget = {}\nup = {}\nvfov_deg = {:?}\n[image]\nwidth = {SIZE}\nheight = \
         {SIZE}\n[render]\nexposure = 1.0\n",
        obj.to_str().unwrap(),
        f(moved.eye),
        f(moved.target),
        f(moved.up),
        moved.vfov_deg
    );
    let scene = dir.join("moved.toml");
    std::fs::write(&scene, toml).unwrap();
    let expected_moved = render_png(&scene, &dir.join("moved.exr"));
    let (changed, _) = difference(&expected_moved, &expected);
    assert!(changed > expected.len() / 4, "the orbit changed only {changed} bytes of the image");
    let shot = screenshot_until(&x, &expected_moved);
    let (differ, most) = difference(&shot, &expected_moved);
    assert!(differ == 0, "after the orbit the window differs from render's PNG in {differ} bytes, by up to {most}");
    writeln!(stdin).unwrap();

    let status = viewer.wait().unwrap();
    let errors = errors.join().unwrap();
    assert!(status.success(), "{status}: {errors}");
    assert!(errors.contains("first picture") && errors.contains("after the move"), "{errors}");
    // `save` wrote what `render` writes for that camera.
    assert_eq!(png_rgb(&saved.with_extension("png")), expected_moved, "the saved PNG is render's");
    let (w, h, aovs) = sensorlight::output::exr::read_channels(&saved, &["sensor_mask", "radiance.R"]).unwrap();
    assert_eq!((w, h), (SIZE as usize, SIZE as usize));
    assert!(aovs[0].contains(&1.0), "the EXR has the AOVs, the sensor mask among them");
}

/// A save writes the picture shown when it is asked: `save a`, then `orbit`, then `save b` wrote the orbited
/// view twice (the first save waited for a render the orbit had already replaced).
#[test]
fn a_save_writes_the_picture_shown_when_it_is_asked() {
    let dir = common::scratch("viewer-saves");
    let x = Xvfb::start();
    let script = dir.join("saves.script");
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    let text = format!("wait done\nsave {}\norbit 30 10\nwait done\nsave {}\nquit\n", a.display(), b.display());
    std::fs::write(&script, text).unwrap();
    let run = x.view(SIZE, &script).output().unwrap();
    assert!(run.status.success(), "{}", common::stderr(&run));
    let expected = render_png(&common::project("scenes/cornell/cornell.toml"), &dir.join("render.exr"));
    assert_eq!(png_rgb(&a.with_extension("png")), expected, "the first save is the scene's own view");
    let (differ, _) = difference(&png_rgb(&b.with_extension("png")), &expected);
    assert!(differ > expected.len() / 4, "the second save is the orbited view ({differ} bytes differ)");
}

#[test]
fn a_window_of_another_shape_shows_the_picture_letterboxed() {
    let dir = common::scratch("viewer-resize");
    let x = Xvfb::start();
    let script = dir.join("resize.script");
    // Twice as wide as the picture: the swapchain is made anew, the picture centred at 1:1 between bars.
    std::fs::write(&script, format!("wait done\nresize {} {SIZE}\nsync\nquit\n", 2 * SIZE)).unwrap();
    let mut viewer =
        x.view(SIZE, &script).stdin(Stdio::piped()).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    let mut lines = BufReader::new(viewer.stdout.take().unwrap()).lines();
    let line = lines.next().and_then(Result::ok).unwrap_or_default();
    assert!(line.starts_with("sync 1"), "{line}");
    let picture = render_png(&common::project("scenes/cornell/cornell.toml"), &dir.join("render.exr"));
    let (w, margin) = (2 * SIZE as usize, SIZE as usize / 2);
    let expected_at = |x: usize, y: usize| -> Option<[u8; 3]> {
        let inside = (margin..margin + SIZE as usize).contains(&x);
        inside.then(|| picture[3 * (y * SIZE as usize + x - margin)..][..3].try_into().unwrap())
    };
    // The bars' grey is the clear value 0.12 as UNORM, rounded either way.
    let matches = |shot: &[u8]| {
        (0..SIZE as usize).all(|y| {
            (0..w).all(|x| {
                let p = &shot[3 * (y * w + x)..][..3];
                match expected_at(x, y) {
                    Some(e) => p == e,
                    None => p.iter().all(|&v| v.abs_diff(31) <= 1),
                }
            })
        })
    };
    let start = Instant::now();
    let mut shot = x.pixels(2 * SIZE, SIZE);
    while !matches(&shot) && start.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(200));
        shot = x.pixels(2 * SIZE, SIZE);
    }
    assert!(matches(&shot), "the window does not show the picture between two grey bars");
    writeln!(viewer.stdin.take().unwrap()).unwrap();
    let mut errors = String::new();
    let _ = viewer.stderr.take().unwrap().read_to_string(&mut errors);
    let status = viewer.wait().unwrap();
    assert!(status.success(), "{status}: {errors}");
}

#[test]
fn ctrl_c_stops_the_viewer_as_it_stops_a_render() {
    let dir = common::scratch("viewer-interrupt");
    let x = Xvfb::start();
    let script = dir.join("interrupt.script");
    std::fs::write(&script, "wait round 1\nsync\nwait done\nquit\n").unwrap();
    let mut viewer =
        x.view(64, &script).stdin(Stdio::piped()).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    let mut lines = BufReader::new(viewer.stdout.take().unwrap()).lines();
    let line = lines.next().and_then(Result::ok).unwrap_or_default();
    assert!(line.starts_with("sync 1"), "{line}");
    // Mid-render (round 1 shown, the script waiting): SIGINT, then the script goes on.
    let kill = Command::new("kill").args(["-INT", &viewer.id().to_string()]).status().unwrap();
    assert!(kill.success());
    writeln!(viewer.stdin.take().unwrap()).unwrap();
    let mut errors = String::new();
    let _ = viewer.stderr.take().unwrap().read_to_string(&mut errors);
    let status = viewer.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{errors}");
    assert!(errors.contains("interrupted") && !errors.contains("validation"), "{errors}");
}

#[test]
fn quitting_mid_render_ends_cleanly() {
    let dir = common::scratch("viewer-quit");
    let x = Xvfb::start();
    let script = dir.join("quit.script");
    // Quit as soon as the first round is shown: the render stops between batches, nothing is left behind.
    std::fs::write(&script, "wait round 1\nquit\n").unwrap();
    let run = x.view(64, &script).output().unwrap();
    let stderr = common::stderr(&run);
    // Exit code 3 would be the validation layer's messages (objects left, a semaphore still in use, …).
    assert_eq!(run.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("validation"), "{stderr}");
    assert!(!common::project("view.exr").exists(), "nothing saved unasked");
}

#[test]
fn without_a_display_the_viewer_says_so_and_points_to_render() {
    let run = common::command()
        .args(["view", "scenes/cornell/cornell.toml"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stderr = common::stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("no display") && stderr.contains("sensorlight render"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    // A display named that is not there: the window system's reason, the same advice.
    let run = common::command().args(["view", "scenes/cornell/cornell.toml"]).env("DISPLAY", ":239").output().unwrap();
    let stderr = common::stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("cannot open a window") && stderr.contains("sensorlight render"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn a_bad_script_is_refused_with_its_line_before_any_window() {
    let dir = common::scratch("viewer-script");
    let script = dir.join("bad.script");
    std::fs::write(&script, "wait done\norbit 20\n").unwrap();
    let run = common::command()
        .args(["view", "scenes/cornell/cornell.toml", "--script", script.to_str().unwrap()])
        .env("DISPLAY", ":239")
        .output()
        .unwrap();
    let stderr = common::stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("bad.script:2") && stderr.contains("takes 2 argument(s)"), "{stderr}");
}

/// `frame K` in a script (as `p`, which plays the path, goes from frame to frame) looks from frame K of the
/// scene's camera path: the save is `render --frame K`'s PNG byte for byte.
#[test]
fn a_scripted_frame_shows_render_s_frame_of_the_path() {
    let dir = common::scratch("viewer-frame");
    let x = Xvfb::start();
    let script = dir.join("frame.script");
    let saved = dir.join("frame.exr");
    std::fs::write(&script, format!("wait done\nframe 12\nwait done\nsave {}\nquit\n", saved.display())).unwrap();
    let size = SIZE.to_string();
    let run = common::command()
        .args(["view", "scenes/cornell/fly.toml", "--width", &size, "--height", &size, "--script"])
        .arg(&script)
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", common::stderr(&run));
    let out = dir.join("render.exr");
    let args = ["render", "scenes/cornell/fly.toml", "-o", out.to_str().unwrap(), "--width", &size, "--height", &size];
    let rendered = common::sensorlight(&[&args[..], &["--frame", "12"]].concat());
    assert!(rendered.status.success(), "{}", common::stderr(&rendered));
    let expected = png_rgb(&dir.join("render.0012.png"));
    assert_eq!(png_rgb(&saved.with_extension("png")), expected, "the viewer's frame 12 is not render's");
    let first = render_png(&common::project("scenes/cornell/fly.toml"), &dir.join("first.exr"));
    assert!(difference(&first, &expected).0 > expected.len() / 4, "frame 12 is not the path's first view");
}
