//! What the `meshlight` command does beyond parsing its arguments: `bake` of one mesh
//! ([`bake_file`]) or of a directory of meshes ([`bake_library`]) with their progress
//! bars ([`progress`]), `inspect` ([`inspect`]), the DAG table both print
//! ([`dag_table`]), `graph` ([`graph`]), `info` ([`info`]) and the bounds every `render` number is checked
//! against before anything runs ([`render_bounds`]).

pub mod bake_file;
pub mod bake_library;
pub mod dag_table;
pub mod graph;
pub mod info;
pub mod inspect;
pub mod progress;
pub mod render_bounds;
