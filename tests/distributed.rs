//! The other schedulers on paper (issue 41, item 6): docs/kubernetes/tiles.json is a Kubernetes manifest
//! (a List of three Jobs, the tiles an Indexed Job), and its commands, run here as the pods would run them
//! (the shared volume a scratch folder, the size made small), give the single render's image byte for byte.

mod common;

use serde_json::Value;

fn jobs() -> Vec<Value> {
    let text = std::fs::read_to_string(common::project("docs/kubernetes/tiles.json")).unwrap();
    let list: Value = serde_json::from_str(&text).expect("the manifest is JSON");
    assert_eq!((list["apiVersion"].as_str(), list["kind"].as_str()), (Some("v1"), Some("List")));
    let items = list["items"].as_array().expect("items").clone();
    for job in &items {
        assert_eq!((job["apiVersion"].as_str(), job["kind"].as_str()), (Some("batch/v1"), Some("Job")), "{job}");
        assert_eq!(job["spec"]["template"]["spec"]["restartPolicy"], "Never", "a Job's pods must not restart");
    }
    items
}

fn command(job: &Value) -> Vec<String> {
    let c = &job["spec"]["template"]["spec"]["containers"][0]["command"];
    c.as_array().expect("a command").iter().map(|w| w.as_str().unwrap().to_owned()).collect()
}

#[test]
fn the_kubernetes_manifest_renders_the_single_render_s_image() {
    let jobs = jobs();
    let name = |j: &Value| j["metadata"]["name"].as_str().unwrap().to_owned();
    let names: Vec<String> = jobs.iter().map(name).collect();
    assert_eq!(names, ["sensorlight-cache", "sensorlight-tiles", "sensorlight-assemble"]);
    let tiles = &jobs[1]["spec"];
    assert_eq!(tiles["completionMode"], "Indexed");
    let n = tiles["completions"].as_u64().expect("completions");

    // As the pods run them: /data is the shared volume; 1024² made 32² to be quick.
    let dir = common::scratch("kubernetes");
    std::fs::create_dir_all(dir.join("out")).unwrap();
    std::os::unix::fs::symlink(common::project("scenes"), dir.join("scenes")).unwrap();
    let here = |w: &str| w.replace("/data", dir.to_str().unwrap()).replace("1024", "32");
    let bin = env!("CARGO_BIN_EXE_sensorlight");
    let run = |words: &[String], index: Option<u64>| {
        let words: Vec<String> = words.iter().map(|w| here(w)).collect();
        let mut c = if words[0] == "sh" {
            let mut c = std::process::Command::new("sh");
            c.args(&words[1..])
                .env("PATH", format!("{}:/usr/bin:/bin", std::path::Path::new(bin).parent().unwrap().display()));
            c
        } else {
            assert_eq!(words[0], "sensorlight", "{words:?}");
            let mut c = common::command();
            c.args(&words[1..]);
            c
        };
        c.env("SENSORLIGHT_VALIDATION", "1").current_dir(env!("CARGO_MANIFEST_DIR"));
        if let Some(i) = index {
            c.env("JOB_COMPLETION_INDEX", i.to_string());
        }
        let out = c.output().unwrap();
        assert!(out.status.success(), "{words:?}: {}", common::stderr(&out));
    };
    run(&command(&jobs[0]), None);
    let tile = command(&jobs[1]);
    assert!(tile.iter().any(|w| w.contains(&format!("--image-tile $((JOB_COMPLETION_INDEX + 1))/{n}"))), "{tile:?}");
    for i in 0..n {
        run(&tile, Some(i));
    }
    let assemble = command(&jobs[2]);
    assert_eq!(assemble.iter().filter(|w| w.ends_with(".exr")).count() as u64, n + 1, "every tile and the output");
    run(&assemble, None);

    let single = dir.join("single.exr");
    let cache = dir.join("out/cache.slc");
    let args =
        ["render", "scenes/cornell/cornell.toml", "-o", single.to_str().unwrap(), "--width", "32", "--height", "32"];
    let out = common::sensorlight(&[&args[..], &["--cache", cache.to_str().unwrap()]].concat());
    assert!(out.status.success(), "{}", common::stderr(&out));
    let bytes = |p: &std::path::Path| std::fs::read(p).unwrap();
    assert!(
        bytes(&single) == bytes(&dir.join("out/cornell.exr")),
        "the manifest's image differs from the single render"
    );
}
