//! Recorded bags of every format: the format's reader streams the messages into [`BagMessages`], then
//! [`bag_assemble`](crate::bag_assemble) makes the log.

use crate::bag_assemble::assemble;
use crate::bag_messages::BagMessages;
use crate::error::LogError;
use crate::format::Format;
use crate::options::ReadOptions;
use crate::sensor_log::SensorLog;
use crate::{mcap_bag, ros1_bag, ros2_folder, sqlite_bag};
use std::io::BufReader;
use std::path::Path;

/// Reads the bag at `path` (a file of `format`, or a ROS 2 bag folder) with `options`.
pub(crate) fn read_bag(path: &Path, format: Format, options: &ReadOptions) -> Result<SensorLog, LogError> {
    let mut bag = BagMessages::new(path, options.max_bytes);
    let open = || {
        std::fs::File::open(path).map(BufReader::new).map_err(|cause| LogError::Io { path: path.to_path_buf(), cause })
    };
    let name = match format {
        Format::Ros1Bag => ros1_bag::read(open()?, &mut bag)?,
        Format::Mcap => mcap_bag::read(open()?, &mut bag)?,
        Format::Sqlite => sqlite_bag::read(path, &mut bag)?,
        Format::Ros2Folder => ros2_folder::read(path, &mut bag)?,
        Format::Carmen => return Err(LogError::UnknownFormat { path: path.to_path_buf() }),
    };
    assemble(bag, options, name)
}
