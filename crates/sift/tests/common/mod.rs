//! Helpers shared by the integration tests.
#[path = "../../src/synth.rs"]
pub mod synth;
