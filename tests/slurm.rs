//! `sensorlight slurm` on a real Slurm (issue 41, items 4 and 5): a private single-node cluster started by
//! the test (`scripts/slurm-local.sh`: munged, slurmctld, slurmd on 127.0.0.1) and stopped after it. The
//! Cornell box in 4 tiles equals the single render byte for byte; 3 frames of a path equal 3 single renders;
//! a task cancelled makes the join fail naming it, and the line it prints completes the image.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// A cluster of its own for one test, stopped when dropped.
struct Cluster {
    dir: PathBuf,
    conf: String,
}

impl Cluster {
    fn start(name: &str) -> Self {
        // Under /tmp: a unix socket's path is at most 107 bytes.
        let dir = std::env::temp_dir().join(format!("sensorlight-slurm-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let run = Command::new("bash")
            .arg(common::project("scripts/slurm-local.sh"))
            .args(["start", dir.to_str().unwrap()])
            .output()
            .expect("cannot run scripts/slurm-local.sh");
        let stdout = String::from_utf8_lossy(&run.stdout).into_owned();
        assert!(run.status.success(), "the cluster did not start: {stdout}{}", common::stderr(&run));
        let conf = stdout.trim().strip_prefix("export SLURM_CONF=").expect("SLURM_CONF").to_owned();
        Self { dir, conf }
    }

    fn command(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", &self.conf);
        c
    }

    /// `sensorlight` with this cluster's Slurm.
    fn sensorlight(&self, args: &[&str]) -> Output {
        let mut c = common::command();
        c.env("SLURM_CONF", &self.conf);
        c.args(args).output().expect("cannot run sensorlight")
    }

    /// Waits until none of `jobs` is queued or running any more.
    fn wait(&self, jobs: &[String]) {
        let start = Instant::now();
        loop {
            let out = self.command("squeue").args(["-h", "-j", &jobs.join(","), "-o", "%i %T"]).output().unwrap();
            let text = String::from_utf8_lossy(&out.stdout).into_owned();
            if out.status.success() && text.trim().is_empty() {
                return;
            }
            assert!(start.elapsed() < Duration::from_secs(300), "jobs {jobs:?} still in the queue: {text}");
            std::thread::sleep(Duration::from_millis(300));
        }
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new("bash")
            .arg(common::project("scripts/slurm-local.sh"))
            .args(["stop", self.dir.to_str().unwrap()])
            .output();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

const FLAGS: [&str; 8] = ["--width", "48", "--height", "36", "--sensor-size", "16", "--strategy", "layered"];

/// Submits `sensorlight slurm` with `args`; returns the job ids it printed.
fn submit(cluster: &Cluster, args: &[&str]) -> Vec<String> {
    let mut all = vec!["slurm"];
    all.extend_from_slice(args);
    all.extend_from_slice(&FLAGS);
    let run = cluster.sensorlight(&all);
    let stderr = common::stderr(&run);
    assert!(run.status.success(), "{all:?}: {stderr}");
    let line = stderr.lines().find(|l| l.starts_with("watch them with: squeue -j ")).expect(&stderr);
    let ids = line.trim_start_matches("watch them with: squeue -j ").split(';').next().unwrap();
    ids.split(',').map(str::to_owned).collect()
}

fn single(out: &Path, scene: &str, extra: &[&str]) {
    let mut args = vec!["render", scene, "-o", out.to_str().unwrap()];
    args.extend_from_slice(&FLAGS);
    args.extend_from_slice(extra);
    let run = common::sensorlight(&args);
    assert!(run.status.success(), "{}", common::stderr(&run));
}

fn bytes(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn log(dir: &Path, name: &str) -> String {
    std::fs::read_to_string(dir.join("logs").join(name)).unwrap_or_default()
}

#[test]
fn tiles_and_frames_through_slurm_equal_single_renders() {
    let cluster = Cluster::start("equal");
    let dir = common::scratch("slurm_equal");

    let out = dir.join("cornell.exr");
    let jobs = submit(&cluster, &["scenes/cornell/cornell.toml", "-o", out.to_str().unwrap(), "--tiles", "4"]);
    assert_eq!(jobs.len(), 3, "a cache job, the array, the join: {jobs:?}");
    cluster.wait(&jobs);
    let job = dir.join("cornell.slurm");
    assert!(out.is_file(), "no image; the join's log: {}", log(&job, "assemble.log"));
    let alone = dir.join("alone.exr");
    single(&alone, "scenes/cornell/cornell.toml", &[]);
    assert!(bytes(&out) == bytes(&alone), "the 4 tiles joined differ from the single render");
    assert!(bytes(&out.with_extension("png")) == bytes(&alone.with_extension("png")), "the PNGs differ");

    let frames = dir.join("fly.exr");
    let jobs = submit(&cluster, &["scenes/cornell/fly.toml", "-o", frames.to_str().unwrap(), "--frames", "10..12"]);
    assert_eq!(jobs.len(), 2, "a cache job and the array: {jobs:?}");
    cluster.wait(&jobs);
    for k in 10..=12 {
        let one = dir.join(format!("one-{k}.exr"));
        single(&one, "scenes/cornell/fly.toml", &["--frame", &k.to_string()]);
        let name = format!("{k:04}.exr");
        let (task, alone) = (frames.with_extension(&name), one.with_extension(&name));
        assert!(
            task.is_file(),
            "frame {k} missing; its log: {}",
            log(&dir.join("fly.slurm"), &format!("task-{k}.log"))
        );
        assert!(bytes(&task) == bytes(&alone), "frame {k} through Slurm differs from its single render");
    }
}

#[test]
fn a_cancelled_task_fails_the_join_naming_it_and_its_rerun_line_completes_the_image() {
    let cluster = Cluster::start("cancel");
    let dir = common::scratch("slurm_cancel");
    let out = dir.join("cornell.exr");
    let scene = "scenes/cornell/cornell.toml";
    // The cache job holds the array back (it is queued behind it): the cancel lands before task 3 runs.
    let jobs = submit(&cluster, &[scene, "-o", out.to_str().unwrap(), "--tiles", "4"]);
    let cancel = cluster.command("scancel").arg(format!("{}_3", jobs[1])).output().unwrap();
    assert!(cancel.status.success(), "{}", common::stderr(&cancel));
    cluster.wait(&jobs);
    let job = dir.join("cornell.slurm");
    let joined = log(&job, "assemble.log");
    assert!(!out.exists(), "the join wrote an image without tile 3");
    assert!(joined.contains("error: task 3 (tile 3/4) failed or did not finish"), "{joined}");
    let rerun = joined.lines().find(|l| l.trim_start().starts_with("sbatch ")).expect(&joined).trim().to_owned();
    assert!(rerun.contains("--array=3 "), "only the failed task is re-run: {rerun}");

    let run = cluster.command("bash").args(["-c", &rerun]).output().unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout).into_owned();
    assert!(run.status.success(), "{rerun}: {stdout}{}", common::stderr(&run));
    let id = stdout.split_whitespace().last().expect(&stdout).to_owned();
    cluster.wait(&[id]);
    assert!(out.is_file(), "the re-run did not complete the image: {}", log(&job, "assemble.log"));
    let alone = dir.join("alone.exr");
    single(&alone, scene, &[]);
    assert!(bytes(&out) == bytes(&alone), "the completed image differs from the single render");
}

/// Without a cluster: what every task would refuse is refused before anything is written; without sbatch
/// the error says `--dry-run` writes the scripts anyway, and `--dry-run` does, for a second submission to
/// refuse to overwrite.
#[test]
fn bad_jobs_are_refused_before_anything_is_written_and_a_dry_run_writes_the_scripts() {
    let dir = common::scratch("slurm_refused");
    let out = dir.join("out.exr");
    let o = out.to_str().unwrap();
    let cornell = "scenes/cornell/cornell.toml";
    for (args, expected) in [
        (vec![cornell, "-o", o, "--tiles", "40", "--height", "36"], "--tiles 40: --image-tile 1/40: 40 tiles of rows"),
        (vec![cornell, "-o", o, "--frames", "0..2"], "--frame and --frames need a camera path"),
        (vec!["scenes/cornell/fly.toml", "-o", o, "--frames", "20..30"], "frame 30 is after the path's end"),
        (vec![cornell, "-o", o], "--tiles <N>"),
        (vec![cornell, "-o", o, "--tiles", "2", "--frames", "0..1"], "cannot be used with"),
        (vec![cornell, "-o", dir.join("out.png").to_str().unwrap(), "--tiles", "2"], "the job writes EXRs"),
    ] {
        let mut all = vec!["slurm"];
        all.extend(args);
        let run = common::sensorlight(&all);
        let stderr = common::stderr(&run);
        assert!(matches!(run.status.code(), Some(1 | 2)) && stderr.contains(expected), "{all:?}: {stderr}");
    }
    // No sbatch on the PATH: said, with --dry-run's way out, and nothing written.
    let run = common::command()
        .env("PATH", "/nonexistent")
        .args(["slurm", cornell, "-o", o, "--tiles", "2"])
        .output()
        .unwrap();
    let stderr = common::stderr(&run);
    assert!(stderr.contains("sbatch is not installed") && stderr.contains("--dry-run writes"), "{stderr}");
    assert!(std::fs::read_dir(&dir).unwrap().next().is_none(), "a refused job wrote something");

    let run = common::sensorlight(&["slurm", cornell, "-o", o, "--tiles", "2", "--dry-run", "--partition", "gpu"]);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let job = dir.join("out.slurm");
    for script in ["submit.sh", "cache.sh", "task.sh", "assemble.sh"] {
        assert!(job.join(script).is_file(), "{script}");
    }
    let submit = std::fs::read_to_string(job.join("submit.sh")).unwrap();
    assert!(submit.contains("--partition=gpu") && submit.contains("--array=1-2"), "{submit}");
    let again = common::sensorlight(&["slurm", cornell, "-o", o, "--tiles", "2", "--dry-run"]);
    assert!(common::stderr(&again).contains("exists (an earlier job chain"), "{}", common::stderr(&again));
}
