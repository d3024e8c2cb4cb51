use thiserror::Error;

/// What can go wrong when assets and instances are added to a scene.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SceneDataError {
    #[error("the scene would hold {requested} {what}, above the limit of {limit}; {advice}")]
    Limit {
        what: &'static str,
        requested: u64,
        limit: u64,
        advice: &'static str,
    },
    #[error("mesh id {0} does not exist in this scene; add the mesh first with `add_mesh`")]
    UnknownMesh(u32),
    #[error("material id {0} does not exist in this scene; add it first with `add_material`")]
    UnknownMaterial(u32),
    #[error("instance id {0} does not exist in this scene")]
    UnknownInstance(u32),
    #[error("asset `{name}` is invalid: {reason}; re-bake it with `meshlight bake`")]
    InvalidAsset { name: String, reason: String },
}
