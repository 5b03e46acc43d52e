//! Files in and out: opening inputs safely, writing outputs atomically, EXR images, and command-line values.

pub mod cache_file;
pub mod cli_values;
pub mod error;
pub mod exr_image;
pub mod input_file;
pub mod memory_files;
pub mod output_file;
