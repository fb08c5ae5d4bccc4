//! Link flags only; see build.rs.
