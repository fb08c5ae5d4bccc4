//! Debian's `libshaderc-dev` ships a `libshaderc_combined.a` (found by the `shaderc-sys` crate) that, unlike
//! upstream's, does not contain glslang and SPIRV-Tools: Debian links them from their own packages instead.
//! This crate adds those static archives to whatever links `shaderc` (here: sensorlight's build script), whole,
//! so that link order does not matter. The versions are the ones Debian built its shaderc against.
//!
//! Without these packages use sensorlight's `shaderc-from-source` feature instead (needs cmake, ~5-10 min).

use std::path::Path;

const ARCHIVES: &[&str] = &[
    "glslang",
    "MachineIndependent",
    "GenericCodeGen",
    "OSDependent",
    "OGLCompiler",
    "SPIRV",
    "glslang-default-resource-limits",
    "SPIRV-Tools-opt",
    "SPIRV-Tools",
];

fn main() {
    let arch = std::env::var("CARGO_CFG_TARGET_ARCH").unwrap();
    let dir = std::env::var("SHADERC_LIB_DIR").unwrap_or_else(|_| format!("/usr/lib/{arch}-linux-gnu"));
    let missing: Vec<String> = std::iter::once("shaderc_combined")
        .chain(ARCHIVES.iter().copied())
        .map(|name| format!("{dir}/lib{name}.a"))
        .filter(|path| !Path::new(path).exists())
        .collect();
    if !missing.is_empty() {
        panic!(
            "system shaderc libraries not found ({}).\n\
             Install them (Debian/Ubuntu: `sudo apt-get install libshaderc-dev glslang-dev spirv-tools`), or build \
             shaderc from source: `cargo build --no-default-features --features shaderc-from-source`.",
            missing.join(", ")
        );
    }
    println!("cargo:rerun-if-env-changed=SHADERC_LIB_DIR");
    println!("cargo:rustc-link-search=native={dir}");
    for name in ARCHIVES {
        println!("cargo:rustc-link-lib=static:+whole-archive={name}");
    }
}
