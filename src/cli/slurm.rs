//! `sensorlight slurm`: a render split over a Slurm cluster, as the job chain Slurm expects — one job that
//! solves the radiance cache, a job array whose task `$SLURM_ARRAY_TASK_ID` renders its tile or frame from
//! that cache, and for tiles one job that joins them — written as scripts into a folder beside the output
//! and submitted with `sbatch`. The folder is the whole state: the scripts, the cache, the tiles, the logs.
//!
//! A task that fails leaves its tile missing (a render writes all or nothing); the join job runs after the
//! array however it ended, names the tasks whose tiles are missing with their logs, and prints the one
//! `sbatch --array=…` line that re-runs only them and joins the image once they are done.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

use anyhow::{Context as _, Result, bail, ensure};
use clap::Args;

use super::args::{EngineFlags, LookFlags};
use super::frames::FrameRange;
use super::tiles::TileSpec;

#[derive(Args)]
#[command(group(clap::ArgGroup::new("split").required(true).args(["tiles", "frames"])))]
pub struct SlurmArgs {
    /// Scene file (TOML), or an OBJ or glTF mesh, as `render` takes it
    scene: PathBuf,
    /// The image: OUT.exr with --tiles (and OUT.png beside it), OUT.####.exr with --frames. The job's
    /// folder is written beside it, OUT.slurm/
    #[arg(short, long, value_name = "OUT.exr")]
    output: PathBuf,
    /// Split the image into N tiles (bands of rows), one array task each, then join them
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    tiles: Option<u32>,
    /// Render frames A to B (both included) of the scene's camera path, one array task each
    #[arg(long, value_name = "A..B")]
    frames: Option<FrameRange>,
    /// The partition to run on (sbatch --partition) [default: the cluster's]
    #[arg(long, value_name = "P")]
    partition: Option<String>,
    /// GPUs for each task (sbatch --gpus-per-task) [default: none asked for]
    #[arg(long, value_name = "G")]
    gpus_per_task: Option<u32>,
    /// Time limit of each job (sbatch --time, e.g. 30:00) [default: the partition's]
    #[arg(long, value_name = "T")]
    time: Option<String>,
    /// The account to charge (sbatch --account)
    #[arg(long, value_name = "A")]
    account: Option<String>,
    /// Another option for every sbatch, as sbatch takes it (repeatable), e.g. --sbatch-arg=--qos=low
    #[arg(long, value_name = "ARG", allow_hyphen_values = true)]
    sbatch_arg: Vec<String>,
    /// Write the scripts (and OUT.slurm/submit.sh, which submits them) without submitting
    #[arg(long)]
    dry_run: bool,
    #[command(flatten)]
    look: LookFlags,
    #[command(flatten)]
    engine: EngineFlags,
}

/// The job folder beside `output`: `out.exr` → `out.slurm`.
fn job_folder(output: &Path) -> PathBuf {
    output.with_extension("slurm")
}

/// `text` quoted for bash.
fn quote(text: &str) -> String {
    if !text.is_empty() && text.chars().all(|c| c.is_ascii_alphanumeric() || "-_./,:=+@%".contains(c)) {
        text.to_owned()
    } else {
        format!("'{}'", text.replace('\'', r"'\''"))
    }
}

fn line(words: &[String]) -> String {
    words.iter().map(|w| quote(w)).collect::<Vec<_>>().join(" ")
}

pub fn run(args: SlurmArgs) -> Result<ExitCode> {
    // What every task would refuse is refused here, before anything is written or submitted.
    let size = (args.look.image.width, args.look.image.height);
    let (scene, params) = super::load_input(&args.scene, &args.look.overrides(), size, &args.look.lights)?;
    let size = args.look.image.size(&scene)?;
    if let Some(n) = args.tiles {
        TileSpec { index: 1, count: n }.rows(size).map_err(|e| anyhow::anyhow!("--tiles {n}: {e:#}"))?;
    }
    if let Some(range) = args.frames {
        super::frames::path_of(&scene, &[Some(range.first), Some(range.last)])?;
    }
    ensure!(
        super::OutputKind::of(&args.output)? == super::OutputKind::Exr,
        "-o {}: the job writes EXRs (with their PNGs); name an .exr file",
        args.output.display()
    );
    let parent = args.output.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let parent =
        parent.canonicalize().with_context(|| format!("-o {}: its folder does not exist", args.output.display()))?;
    let output = parent.join(args.output.file_name().context("-o names no file")?);
    let dir = job_folder(&output);
    ensure!(
        !dir.exists(),
        "{} exists (an earlier job chain, with its tiles and logs): remove it, or name another -o",
        dir.display()
    );
    let scene_path = args.scene.canonicalize().with_context(|| format!("cannot find {}", args.scene.display()))?;
    let binary = std::env::current_exe().context("cannot find the sensorlight binary to run on the nodes")?;
    let gi = params.estimator.indirect.bounces().is_some();
    let chain = Chain {
        binary: binary.display().to_string(),
        scene: scene_path.display().to_string(),
        output: output.display().to_string(),
        dir: dir.clone(),
        flags: [args.look.to_args()?, args.engine.to_args()].concat(),
        sbatch: sbatch_options(&args),
        gi,
        split: match (args.tiles, args.frames) {
            (Some(n), _) => Split::Tiles(n),
            (None, Some(range)) => Split::Frames(range),
            (None, None) => unreachable!("clap requires one"),
        },
    };
    if !args.dry_run && Command::new("sbatch").arg("--version").output().is_err() {
        bail!(
            "sbatch is not installed here (Slurm's client; Debian: slurm-client), so nothing can be submitted; \
             --dry-run writes the job's scripts anyway (into {}), to submit from a machine that has sbatch",
            dir.display()
        );
    }
    chain.write()?;
    let submit = dir.join("submit.sh");
    if args.dry_run {
        say!("wrote the job chain into {}; submit it with: bash {}", dir.display(), submit.display());
        return Ok(ExitCode::SUCCESS);
    }
    let run = Command::new("bash").arg(&submit).output().context("cannot run bash")?;
    let stdout = String::from_utf8_lossy(&run.stdout);
    if !run.status.success() {
        bail!(
            "sbatch refused the job chain: {}{}(the scripts stay in {}; submit them again with: bash {})",
            String::from_utf8_lossy(&run.stderr),
            stdout,
            dir.display(),
            submit.display()
        );
    }
    let ids: Vec<&str> = stdout.lines().filter_map(|l| l.split_whitespace().nth(1)).collect();
    say!("submitted {}", stdout.lines().collect::<Vec<_>>().join(", "));
    say!("watch them with: squeue -j {}; logs in {}/logs/", ids.join(","), dir.display());
    match chain.split {
        Split::Tiles(_) => say!("the image: {} (and its PNG), once the join job is done", output.display()),
        Split::Frames(r) => say!(
            "the frames: {} to {}",
            super::frames::numbered(&output, r.first).display(),
            super::frames::numbered(&output, r.last).display()
        ),
    }
    Ok(ExitCode::SUCCESS)
}

/// The options every sbatch of the chain takes.
fn sbatch_options(args: &SlurmArgs) -> Vec<String> {
    let mut options = Vec::new();
    options.extend(args.partition.as_ref().map(|p| format!("--partition={p}")));
    options.extend(args.gpus_per_task.map(|g| format!("--gpus-per-task={g}")));
    options.extend(args.time.as_ref().map(|t| format!("--time={t}")));
    options.extend(args.account.as_ref().map(|a| format!("--account={a}")));
    options.extend(args.sbatch_arg.iter().cloned());
    options
}

#[derive(Clone, Copy)]
enum Split {
    Tiles(u32),
    Frames(FrameRange),
}

/// The job chain's scripts, all paths absolute (a node runs them from anywhere).
struct Chain {
    binary: String,
    scene: String,
    output: String,
    dir: PathBuf,
    /// `render`'s flags as given, passed to every job.
    flags: Vec<String>,
    sbatch: Vec<String>,
    /// Whether the render has a radiance cache to solve first.
    gi: bool,
    split: Split,
}

impl Chain {
    fn path(&self, name: &str) -> String {
        self.dir.join(name).display().to_string()
    }

    /// Writes the folder whole: into a temporary sibling, then renamed.
    fn write(&self) -> Result<()> {
        let temp = self.dir.with_extension("slurm.partial");
        let _ = std::fs::remove_dir_all(&temp);
        let made = (|| -> Result<()> {
            std::fs::create_dir_all(temp.join("logs"))?;
            std::fs::create_dir_all(temp.join("tiles"))?;
            let mut scripts = vec![("task.sh", self.task()), ("submit.sh", self.submit())];
            if self.gi {
                scripts.push(("cache.sh", self.cache()));
            }
            if let Split::Tiles(_) = self.split {
                scripts.push(("assemble.sh", self.assemble()));
            }
            for (name, text) in scripts {
                let path = temp.join(name);
                std::fs::write(&path, text)?;
                use std::os::unix::fs::PermissionsExt as _;
                std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755))?;
            }
            std::fs::rename(&temp, &self.dir)?;
            Ok(())
        })();
        if made.is_err() {
            let _ = std::fs::remove_dir_all(&temp);
        }
        made.with_context(|| format!("cannot write the job folder {}", self.dir.display()))
    }

    fn header(&self, what: &str) -> String {
        format!("#!/usr/bin/env bash\n# Written by `sensorlight slurm`: {what}\nset -euo pipefail\n")
    }

    fn cache_flags(&self) -> Vec<String> {
        if self.gi { vec!["--cache".into(), self.path("cache.slc")] } else { Vec::new() }
    }

    fn cache(&self) -> String {
        let mut words =
            vec![self.binary.clone(), "cache".into(), self.scene.clone(), "-o".into(), self.path("cache.slc")];
        words.extend(self.flags.iter().cloned());
        format!("{}{}\n", self.header("solves the radiance cache once, for every task."), line(&words))
    }

    fn task(&self) -> String {
        let mut s = self.header("one array task: its tile or frame is $SLURM_ARRAY_TASK_ID.");
        s += "i=${SLURM_ARRAY_TASK_ID:?run by sbatch --array (submit.sh)}\n";
        let mut words = vec![self.binary.clone(), "render".into(), self.scene.clone()];
        let (output, split) = match self.split {
            Split::Tiles(n) => (self.path("tiles/tile-$i.exr"), vec!["--image-tile".to_owned(), format!("$i/{n}")]),
            Split::Frames(_) => (self.output.clone(), vec!["--frame".to_owned(), "$i".to_owned()]),
        };
        words.extend(self.flags.iter().cloned());
        words.extend(self.cache_flags());
        // `$i` must expand: those words are written in double quotes.
        let _ = writeln!(
            s,
            "{} -o \"{output}\" {}",
            line(&words),
            split.iter().map(|w| format!("\"{w}\"")).collect::<Vec<_>>().join(" ")
        );
        s
    }

    fn assemble(&self) -> String {
        let Split::Tiles(n) = self.split else { unreachable!("frames are not joined") };
        let options = self.sbatch.iter().map(|o| quote(o)).collect::<Vec<_>>().join(" ");
        let spaced = if options.is_empty() { String::new() } else { format!("{options} ") };
        // The line a user runs: the failed tasks again (LIST, filled in below), then this join after them.
        let rerun = format!(
            "sbatch {spaced}--job-name=sensorlight-assemble --output={} --dependency=afterany:$(sbatch --parsable \
             --array=LIST {spaced}--job-name=sensorlight-tasks --output={} {}) {}",
            quote(&self.path("logs/assemble.log")),
            quote(&self.path("logs/task-%a.log")),
            quote(&self.path("task.sh")),
            quote(&self.path("assemble.sh"))
        );
        let cache_check = if self.gi {
            format!(
                "if [ ! -f {} ]; then\n    echo \"error: the cache job failed, so no task could run: its log is \
                 $dir/logs/cache.log; submit the chain again with: bash $dir/submit.sh\" >&2\n    exit 1\nfi\n",
                quote(&self.path("cache.slc"))
            )
        } else {
            String::new()
        };
        let mut s = self.header(
            "joins the tiles once the array is done, however it ended; names the tasks whose tiles are missing.",
        );
        let _ = write!(
            s,
            r#"dir={dir}
n={n}
{cache_check}missing=()
for i in $(seq 1 "$n"); do
    [ -f "$dir/tiles/tile-$i.exr" ] || missing+=("$i")
done
if [ ${{#missing[@]}} -gt 0 ]; then
    for i in "${{missing[@]}}"; do
        echo "error: task $i (tile $i/$n) failed or did not finish: its log is $dir/logs/task-$i.log" >&2
    done
    list=$(IFS=,; echo "${{missing[*]}}")
    rerun={rerun}
    echo "re-run only those tasks, and then this join, with:" >&2
    echo "  ${{rerun//LIST/$list}}" >&2
    exit 1
fi
tiles=()
for i in $(seq 1 "$n"); do tiles+=("$dir/tiles/tile-$i.exr"); done
{binary} assemble "${{tiles[@]}}" -o {output}{no_png}
"#,
            dir = quote(&self.dir.display().to_string()),
            rerun = quote(&rerun),
            binary = quote(&self.binary),
            output = quote(&self.output),
            no_png = if self.flags.iter().any(|f| f == "--no-png") { " --no-png" } else { "" },
        );
        s
    }

    fn submit(&self) -> String {
        let options = self.sbatch.iter().map(|o| quote(o)).collect::<Vec<_>>().join(" ");
        let log = |name: &str| quote(&self.path(&format!("logs/{name}")));
        let mut s = self.header("submits the chain; prints each job's id.");
        let _ = writeln!(s, "options=({options})");
        s += "id() { sbatch --parsable \"${options[@]}\" \"$@\" | cut -d';' -f1; }\n";
        let mut after = String::new();
        if self.gi {
            let _ = writeln!(
                s,
                "cache=$(id --job-name=sensorlight-cache --output={} {})",
                log("cache.log"),
                quote(&self.path("cache.sh"))
            );
            s += "echo \"cache $cache\"\n";
            after = "--dependency=afterok:$cache --kill-on-invalid-dep=yes ".into();
        }
        let (first, last) = match self.split {
            Split::Tiles(n) => (1, n),
            Split::Frames(r) => (r.first, r.last),
        };
        let _ = writeln!(
            s,
            "tasks=$(id --job-name=sensorlight-tasks --array={first}-{last} {after}--output={} {})",
            log("task-%a.log"),
            quote(&self.path("task.sh"))
        );
        s += "echo \"tasks $tasks\"\n";
        if let Split::Tiles(_) = self.split {
            let _ = writeln!(
                s,
                "assemble=$(id --job-name=sensorlight-assemble --dependency=afterany:$tasks --output={} {})",
                log("assemble.log"),
                quote(&self.path("assemble.sh"))
            );
            s += "echo \"assemble $assemble\"\n";
        }
        s
    }
}
