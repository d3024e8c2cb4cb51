//! What the `meshlight` command does beyond parsing its arguments: `bake` over a
//! directory of meshes ([`bake_library`]), `info` ([`info`]) and the bounds every
//! `render` number is checked against before anything runs ([`render_bounds`]).

pub mod bake_library;
pub mod info;
pub mod render_bounds;
