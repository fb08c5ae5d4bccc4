//! Shared test helpers: a validated GPU, the CLI binary, scratch directories.
#![allow(dead_code)] // each test binary uses a different subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Arc;

use sensorlight::vk::{Device, DeviceOptions};

/// Runs `work` on the default device with the Khronos validation layer on, then destroys the device and
/// fails the test if the layer reported anything (including objects left undestroyed).
pub fn gpu<R>(work: impl FnOnce(&Arc<Device>) -> R) -> R {
    let device = Device::new(&DeviceOptions { validation: true, device_index: None })
        .expect("tests need a Vulkan device and the validation layer (see README)");
    let log = device.validation_log().clone();
    let result = work(&device);
    drop(device);
    let messages = log.messages();
    assert!(messages.is_empty(), "validation layer reported {} message(s):\n{}", messages.len(), messages.join("\n"));
    result
}

/// A fresh, empty directory for one test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs the `sensorlight` binary with validation on.
pub fn sensorlight(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sensorlight"))
        .args(args)
        .env("SENSORLIGHT_VALIDATION", "1")
        .output()
        .expect("cannot run sensorlight")
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

pub fn project(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}
