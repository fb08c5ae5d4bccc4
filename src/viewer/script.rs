//! `view --script FILE`: the viewer driven by a file instead of a hand, for tests and timings. One command
//! a line; `#` starts a comment.
//!
//! ```text
//! wait done              # until the render in progress has presented its final image
//! wait round 2           # until it has presented round 2 (or is done)
//! sync                   # print `sync N <camera>` on stdout, then read a line from stdin
//! orbit 20 0             # degrees: about the world's up, then the camera's right (Orbit::orbit)
//! pan 0.1 0              # view heights at the target's distance, right and up
//! dolly 0.8              # the distance to the target × 0.8
//! exposure 1.5           # stops
//! show radiance          # image | radiance | sensors | surfaces | emission
//! save out.exr           # once done: the EXR (image and AOVs) and the PNG beside it, as `render` writes
//! resize 320 240         # ask for a window of that many pixels (the picture is letterboxed in it)
//! frame 12             # the camera of frame 12 of the scene's camera path ([path])
//! play                   # play the path, a frame as each render is done (again: stop)
//! quit
//! ```

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context as _, Result, bail};

use super::display::Show;
use super::progress::wait_for_stdin;
use super::window::Action;

/// One line of a script.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    WaitDone,
    WaitRound(u32),
    Sync,
    Orbit {
        yaw_deg: f32,
        pitch_deg: f32,
    },
    Pan {
        x: f32,
        y: f32,
    },
    Dolly(f32),
    Exposure(f32),
    Show(Show),
    Save(PathBuf),
    Resize {
        width: u32,
        height: u32,
    },
    /// The camera of this frame of the scene's camera path.
    Frame(u32),
    /// Play the path (or stop).
    Play,
    Quit,
}

/// Reads the script at `path`; an error names the file and line.
pub fn load(path: &Path) -> Result<Vec<Command>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read the script {}", path.display()))?;
    parse(&text).map_err(|(line, e)| anyhow::anyhow!("{}:{line}: {e}", path.display()))
}

/// The commands of `text`, or the 1-based line of the first bad one and why.
pub fn parse(text: &str) -> Result<Vec<Command>, (usize, anyhow::Error)> {
    let mut commands = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let words: Vec<&str> = line.split('#').next().unwrap_or("").split_whitespace().collect();
        if let Some((&verb, args)) = words.split_first() {
            commands.push(command(verb, args).map_err(|e| (i + 1, e))?);
        }
    }
    Ok(commands)
}

fn command(verb: &str, args: &[&str]) -> Result<Command> {
    let number = |i: usize| -> Result<f32> {
        let word = args.get(i).with_context(|| format!("`{verb}` needs {} number(s)", i + 1))?;
        match word.parse::<f32>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => bail!("`{verb}`: '{word}' is not a finite number"),
        }
    };
    let count = |n: usize| -> Result<()> {
        match args.len() == n {
            true => Ok(()),
            false => bail!("`{verb}` takes {n} argument(s), got {}", args.len()),
        }
    };
    Ok(match verb {
        "wait" => match args {
            ["done"] => Command::WaitDone,
            ["round", n] => match n.parse::<u32>() {
                Ok(n) if n >= 1 => Command::WaitRound(n),
                _ => bail!("`wait round N`: N must be a round number from 1, got '{n}'"),
            },
            _ => bail!("expected `wait done` or `wait round N`"),
        },
        "sync" => count(0).map(|_| Command::Sync)?,
        "orbit" => count(2).and_then(|_| Ok(Command::Orbit { yaw_deg: number(0)?, pitch_deg: number(1)? }))?,
        "pan" => count(2).and_then(|_| Ok(Command::Pan { x: number(0)?, y: number(1)? }))?,
        "dolly" => {
            count(1)?;
            match number(0)? {
                f if f > 0.0 => Command::Dolly(f),
                f => bail!("`dolly`: the factor must be above 0, got {f}"),
            }
        }
        "exposure" => count(1).and_then(|_| number(0)).map(Command::Exposure)?,
        "show" => {
            count(1)?;
            Command::Show(Show::from_word(args[0]).with_context(|| {
                let all: Vec<&str> = Show::ALL.iter().map(|s| s.word()).collect();
                format!("`show`: '{}' is none of {}", args[0], all.join(", "))
            })?)
        }
        "save" => count(1).map(|_| Command::Save(PathBuf::from(args[0])))?,
        "resize" => {
            count(2)?;
            let pixels = |word: &str| match word.parse::<u32>() {
                Ok(n) if (1..=16_384).contains(&n) => Ok(n),
                _ => Err(anyhow::anyhow!("`resize`: '{word}' is not a size in pixels from 1 to 16384")),
            };
            Command::Resize { width: pixels(args[0])?, height: pixels(args[1])? }
        }
        "frame" => match args {
            [k] => Command::Frame(k.parse().map_err(|_| anyhow::anyhow!("`frame K`: '{k}' is not a frame number"))?),
            _ => bail!("`frame` takes 1 argument, the frame's number"),
        },
        "play" => count(0).map(|_| Command::Play)?,
        "quit" => count(0).map(|_| Command::Quit)?,
        _ => bail!(
            "unknown command '{verb}' (wait, sync, orbit, pan, dolly, exposure, show, save, resize, frame, play, quit)"
        ),
    })
}

/// A script and how far it got.
pub(super) struct ScriptRun {
    pub(super) commands: Vec<Command>,
    pub(super) next: usize,
    pub(super) syncs: u32,
    /// A `resize` asked for this size at this time: the script waits until the window has it (or a while).
    pub(super) resizing: Option<((u32, u32), Instant)>,
}

/// How long a script's `resize` waits for the window system to grant the size before it goes on.
const RESIZE_WAIT: Duration = Duration::from_secs(5);

impl super::Session<'_> {
    /// The next script commands that can run now, as actions. A `wait` stops the script until it is met.
    pub(super) fn step_script(&mut self) -> Vec<Action> {
        let mut actions = Vec::new();
        let (done, rounds, size) = (self.this.done(), self.this.rounds, self.window.size());
        let Some(run) = &mut self.script else { return actions };
        if let Some((wanted, asked)) = run.resizing {
            if size != wanted && asked.elapsed() < RESIZE_WAIT {
                return actions;
            }
            run.resizing = None;
        }
        while let Some(command) = run.commands.get(run.next) {
            let action = match command {
                Command::WaitDone if !done => break,
                Command::WaitRound(n) if !done && rounds < *n => break,
                // Saved once done: later commands wait for it.
                Command::Save(_) if !done => break,
                Command::WaitDone | Command::WaitRound(_) => None,
                Command::Sync => {
                    run.syncs += 1;
                    let o = &self.orbit;
                    let line = format!(
                        "sync {} {{\"eye\":{:?},\"target\":{:?},\"up\":{:?},\"vfov_deg\":{:?}}}",
                        run.syncs,
                        o.eye.to_array(),
                        o.target.to_array(),
                        o.up.to_array(),
                        o.vfov_deg
                    );
                    wait_for_stdin(&line);
                    None
                }
                Command::Orbit { yaw_deg, pitch_deg } => {
                    Some(Action::Orbit { yaw_deg: *yaw_deg, pitch_deg: *pitch_deg })
                }
                Command::Pan { x, y } => Some(Action::Pan { x: *x, y: *y }),
                Command::Dolly(f) => Some(Action::Dolly(*f)),
                Command::Exposure(stops) => Some(Action::ExposureTo(*stops)),
                Command::Show(show) => Some(Action::Show(*show)),
                Command::Save(path) => Some(Action::Save(Some(path.clone()))),
                Command::Resize { width, height } => {
                    run.resizing = Some(((*width, *height), Instant::now()));
                    Some(Action::Resize(*width, *height))
                }
                Command::Frame(k) => Some(Action::Frame(*k)),
                Command::Play => Some(Action::Play),
                Command::Quit => Some(Action::Quit),
            };
            run.next += 1;
            let moves = matches!(
                action,
                Some(Action::Orbit { .. } | Action::Pan { .. } | Action::Dolly(_) | Action::Frame(_) | Action::Play)
            );
            actions.extend(action);
            // A move starts a render, a resize waits for the window: what follows waits for either.
            if moves || run.resizing.is_some() {
                break;
            }
        }
        actions
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_command_parses_and_comments_and_blank_lines_are_skipped() {
        let text = "# a test\n\nwait round 2\nwait done # then\nsync\norbit 20 -5\npan 0.1 0\ndolly 0.8\n\
                    exposure -1.5\nshow sensors\nsave out.exr\nresize 320 240\nquit\n";
        let commands = parse(text).unwrap();
        assert_eq!(
            commands,
            [
                Command::WaitRound(2),
                Command::WaitDone,
                Command::Sync,
                Command::Orbit { yaw_deg: 20.0, pitch_deg: -5.0 },
                Command::Pan { x: 0.1, y: 0.0 },
                Command::Dolly(0.8),
                Command::Exposure(-1.5),
                Command::Show(Show::Sensors),
                Command::Save(PathBuf::from("out.exr")),
                Command::Resize { width: 320, height: 240 },
                Command::Quit,
            ]
        );
    }

    #[test]
    fn a_bad_line_is_named_with_why() {
        for (text, line, why) in [
            ("sync\nspin 3", 2, "unknown command 'spin'"),
            ("orbit 20", 1, "takes 2 argument(s), got 1"),
            ("wait\n", 1, "expected `wait done`"),
            ("wait round 0", 1, "round number from 1"),
            ("dolly -1", 1, "above 0"),
            ("pan x 0", 1, "'x' is not a finite number"),
            ("exposure inf", 1, "not a finite number"),
            ("\n\nshow depth", 3, "'depth' is none of image, radiance"),
            ("resize 0 10", 1, "not a size in pixels"),
        ] {
            let (at, e) = parse(text).unwrap_err();
            assert_eq!(at, line, "{text}");
            assert!(format!("{e:#}").contains(why), "{text}: {e:#}");
        }
    }
}
