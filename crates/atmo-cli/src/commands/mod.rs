//! One module a subcommand: its arguments and `run`.

pub mod assemble;
pub mod clouds;
pub mod compare;
pub mod dmx;
pub mod inspect;
pub mod precompute;
pub mod shafts;
pub mod sky;
mod sky_table;
pub mod sun;
pub mod view;
