//! One module per subcommand.

pub mod log;
pub mod map;
pub mod merge;
pub mod run;
pub mod slam;
