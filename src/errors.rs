//! How an error reaches the user: one line, each cause once.

/// The error and its causes joined by ": ", like anyhow's `{:#}`, but a cause that repeats what the message
/// before it already said is left out. Libraries such as `exr` and `png` print an I/O error as their own
/// message and also return it as its source, which would show "No space left on device" twice.
pub fn message(error: &anyhow::Error) -> String {
    let mut out = String::new();
    let mut previous = String::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if !previous.is_empty() && previous.contains(&text) {
            continue;
        }
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&text);
        previous = text;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::Context as _;

    /// An EXR written to a full disk: exr's error displays the I/O error and returns it as its source.
    #[test]
    fn a_repeated_cause_is_said_once() {
        let full = std::io::Error::from_raw_os_error(28);
        let exr_error: Result<(), exr::error::Error> = Err(full.into());
        let error = exr_error.context("writing out.exr").unwrap_err();
        assert_eq!(format!("{error:#}").matches("No space left on device").count(), 2, "anyhow repeats it");
        let text = message(&error);
        assert_eq!(text, "writing out.exr: No space left on device (os error 28)");
        let plain = anyhow::anyhow!("inner").context("middle").context("outer");
        assert_eq!(message(&plain), "outer: middle: inner");
    }
}
