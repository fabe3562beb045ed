//! The plugin's tests, one binary (each test binary of Bevy's size takes a link of its
//! own): Bevy renders headless on whatever adapter there is and the pictures are read
//! back and held to atmo's own.

mod aerial;
mod beams;
mod clouds;
mod common;
mod light;
mod sky;

#[path = "../../examples/scene/mod.rs"]
mod scene;
