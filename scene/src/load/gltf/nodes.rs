//! Expanding the node tree of a glTF scene into mesh instances, safely for any input: the
//! walk is iterative (a deep chain cannot overflow the stack), a node that is its own
//! descendant is refused, and the expansion is counted before it is done, so a tree that
//! shares subtrees to instance a mesh billions of times is refused by its size rather
//! than by running out of memory.

use glam::{Mat4, Quat, Vec3};
use gltf::json::Root;

use crate::mesh::MAX_TRIANGLES;

/// Most node instances one scene may expand to. A real scene has one per node; more
/// means subtrees shared many times over.
pub const MAX_NODE_INSTANCES: u64 = 1 << 20;

/// A node reached by one path through the node tree, with what it carries.
pub struct Placement {
    /// The node (`None` for a mesh a file without scenes places untransformed).
    pub node: Option<usize>,
    /// The mesh it places, if any.
    pub mesh: Option<usize>,
    /// The camera it carries, if any.
    pub camera: Option<usize>,
    /// Its world transform: its ancestors' transforms and its own.
    pub transform: Mat4,
}

/// Why a node tree cannot be expanded; turned into [`crate::SceneError`] by the caller,
/// which knows the path.
pub enum NodeError {
    MissingNode { parent: Option<usize>, node: usize },
    MissingMesh { node: usize, mesh: usize },
    Cycle { node: usize, through: usize },
    BadTransform { node: usize },
    TooManyInstances { count: u64 },
    TooManyTriangles { count: u64 },
}

/// The nodes of the scene rooted at `roots` that carry a mesh or a camera, in depth-first
/// order. `mesh_triangles[m]` is mesh `m`'s triangle count as its accessors declare it,
/// which bounds the expansion: with `budget`, more than that many triangles placed in all
/// is refused before anything is expanded (a scene kept as instances places them
/// without copying, and gives none).
pub fn expand(
    root: &Root,
    roots: &[usize],
    mesh_triangles: &[u64],
    budget: Option<u64>,
) -> Result<Vec<Placement>, NodeError> {
    let nodes = &root.nodes;
    let children = |n: usize| -> &[gltf::json::Index<gltf::json::Node>] {
        nodes[n].children.as_deref().unwrap_or(&[])
    };
    for &r in roots {
        if r >= nodes.len() {
            return Err(NodeError::MissingNode {
                parent: None,
                node: r,
            });
        }
    }
    // Post-order walk over every node reachable from the roots, computing how many
    // instances and triangles its subtree expands to (saturating), and finding cycles.
    const UNSEEN: u8 = 0;
    const ON_PATH: u8 = 1;
    const DONE: u8 = 2;
    let mut state = vec![UNSEEN; nodes.len()];
    let mut subtree = vec![(0u64, 0u64); nodes.len()];
    for &r in roots {
        if state[r] == DONE {
            continue;
        }
        // (node, next child to visit)
        let mut stack: Vec<(usize, usize)> = vec![(r, 0)];
        state[r] = ON_PATH;
        while let Some(&mut (n, ref mut next)) = stack.last_mut() {
            let kids = children(n);
            if *next < kids.len() {
                let c = kids[*next].value();
                *next += 1;
                if c >= nodes.len() {
                    return Err(NodeError::MissingNode {
                        parent: Some(n),
                        node: c,
                    });
                }
                match state[c] {
                    ON_PATH => {
                        return Err(NodeError::Cycle {
                            node: c,
                            through: n,
                        });
                    }
                    UNSEEN => {
                        state[c] = ON_PATH;
                        stack.push((c, 0));
                    }
                    _ => {}
                }
                continue;
            }
            let own = match nodes[n].mesh {
                Some(m) => *mesh_triangles
                    .get(m.value())
                    .ok_or(NodeError::MissingMesh {
                        node: n,
                        mesh: m.value(),
                    })?,
                None => 0,
            };
            let (mut instances, mut triangles) = (1u64, own);
            for c in kids {
                let (i, t) = subtree[c.value()];
                instances = instances.saturating_add(i);
                triangles = triangles.saturating_add(t);
            }
            subtree[n] = (instances, triangles);
            state[n] = DONE;
            stack.pop();
        }
    }
    let (mut instances, mut triangles) = (0u64, 0u64);
    for &r in roots {
        instances = instances.saturating_add(subtree[r].0);
        triangles = triangles.saturating_add(subtree[r].1);
    }
    if instances > MAX_NODE_INSTANCES {
        return Err(NodeError::TooManyInstances { count: instances });
    }
    if let Some(budget) = budget
        && triangles > MAX_TRIANGLES.min(budget)
    {
        return Err(NodeError::TooManyTriangles { count: triangles });
    }

    // Now bounded: expand, iteratively.
    let mut out = Vec::new();
    let mut stack: Vec<(usize, Mat4)> = roots.iter().rev().map(|&r| (r, Mat4::IDENTITY)).collect();
    while let Some((n, parent)) = stack.pop() {
        let world =
            parent * local_transform(&nodes[n]).ok_or(NodeError::BadTransform { node: n })?;
        let (mesh, camera) = (nodes[n].mesh, nodes[n].camera);
        if mesh.is_some() || camera.is_some() {
            out.push(Placement {
                node: Some(n),
                mesh: mesh.map(|m| m.value()),
                camera: camera.map(|c| c.value()),
                transform: world,
            });
        }
        stack.extend(children(n).iter().rev().map(|c| (c.value(), world)));
    }
    Ok(out)
}

/// The node's matrix, or its translation · rotation · scale; `None` when not finite.
fn local_transform(node: &gltf::json::Node) -> Option<Mat4> {
    let m = match node.matrix {
        Some(m) => Mat4::from_cols_array(&m),
        None => {
            let t = Vec3::from(node.translation.unwrap_or([0.0; 3]));
            let r = node
                .rotation
                .map_or(Quat::IDENTITY, |q| Quat::from_array(q.0));
            let s = Vec3::from(node.scale.unwrap_or([1.0; 3]));
            if !r.is_finite() {
                return None;
            }
            Mat4::from_scale_rotation_translation(s, r.normalize(), t)
        }
    };
    m.is_finite().then_some(m)
}
