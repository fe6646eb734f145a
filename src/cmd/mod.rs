//! One module per subcommand.

pub mod features;
pub mod log;
pub mod map;
pub mod merge;
pub mod run;
pub mod slam;
pub mod study;
pub mod viz;
