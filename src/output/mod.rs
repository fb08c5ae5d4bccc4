//! What the program writes: EXR (linear radiance and AOVs), PNG, plots, always atomically; results on
//! standard output.

pub mod atomic;
pub mod exr;
pub mod hdr;
pub mod plot;
pub mod png;
pub mod stdout;

/// `value` as pretty JSON ending in a newline, as text files should (POSIX tools, `cat`, diffs).
pub fn json_text<T: serde::Serialize + ?Sized>(value: &T) -> serde_json::Result<String> {
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    Ok(text)
}
