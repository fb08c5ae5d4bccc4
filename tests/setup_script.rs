//! `scripts/setup.sh --lavapipe-backports` takes Debian's backports from the machine's own apt sources (the
//! same mirror, suite naming and key), one-line or deb822: its `backports_source` function, run on sample
//! source files.

mod common;

use std::process::Command;

/// `backports_source` from the setup script, run on `files` (written into a scratch directory).
fn backports_source(name: &str, files: &[(&str, &str)]) -> (bool, String, String) {
    let dir = common::scratch(name);
    let mut paths = Vec::new();
    for (file, text) in files {
        std::fs::write(dir.join(file), text).unwrap();
        paths.push(dir.join(file).display().to_string());
    }
    let script = common::project("scripts/setup.sh");
    let out = Command::new("bash")
        .arg("-c")
        .arg(r#"source <(sed -n '/^backports_source()/,/^}/p' "$0") && backports_source "$@""#)
        .arg(script)
        .args(&paths)
        .output()
        .unwrap();
    (out.status.success(), String::from_utf8_lossy(&out.stdout).trim().to_owned(), common::stderr(&out))
}

#[test]
fn the_backports_line_follows_the_configured_mirror() {
    // A local mirror in the one-line format, its options kept.
    let (ok, line, _) = backports_source(
        "setup-one-line",
        &[("sources.list", "# mirror\ndeb [signed-by=/k.gpg] http://mirror.local/debian/ bookworm main contrib\n")],
    );
    assert!(ok);
    assert_eq!(line, "deb [signed-by=/k.gpg] http://mirror.local/debian/ bookworm-backports main");
    // deb822: a third-party source with a `main` component is passed over, -updates too; the proxy's URI
    // and the key are taken; a stable alias keeps its name.
    let sources = "Types: deb\nURIs: https://deb.nodesource.com/node_20.x\nSuites: nodistro\nComponents: main\n\n\
                   Types: deb\n# snapshot\nURIs: http://proxy:3142/debian\nSuites: oldstable-updates oldstable\n\
                   Components: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n";
    let (ok, line, _) = backports_source("setup-deb822", &[("debian.sources", sources)]);
    assert!(ok);
    assert_eq!(
        line,
        "deb [signed-by=/usr/share/keyrings/debian-archive-keyring.gpg] http://proxy:3142/debian oldstable-backports main"
    );
}

#[test]
fn no_debian_source_is_an_error_that_says_what_to_do() {
    let disabled = "Types: deb\nURIs: http://x/debian\nSuites: stable\nComponents: main\nEnabled: no\n";
    let security = "deb http://x/debian-security stable-security main\n";
    let (ok, line, err) = backports_source("setup-none", &[("a.sources", disabled), ("b.list", security)]);
    assert!(!ok && line.is_empty(), "{line}");
    assert!(err.contains("no apt source for Debian") && err.contains("SENSORLIGHT_BACKPORTS_SOURCE"), "{err}");
}
