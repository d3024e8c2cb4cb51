//! Programs a pass declares in `setup` and fetches by name in `record`: compute pipelines,
//! vertex + fragment pipelines, and mesh (+ task) + fragment pipelines.
//!
//! Declaring them at compile time puts the exact variant that runs (shader, entry points,
//! defs) into the plan and its dumps, instead of deciding it again while recording.

use crate::layout::BindingLayout;
use meshlight_shaders::{PassShader, ShaderDef, ShaderDefs};
use serde::Serialize;

/// Where a colour or depth attachment of a render program comes from: a slot of the
/// pass, or a scratch texture it declared (the masked dummy target of a raster that only
/// writes storage).
pub type TargetName = &'static str;

/// One colour target of a render program.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ColorTarget {
    /// The slot or scratch texture drawn into.
    pub target: TargetName,
    /// `ColorWrites::empty()` for a target that exists only because a render pipeline must
    /// have one.
    pub write_mask: wgpu::ColorWrites,
    /// Blending with what the target holds; `None` replaces it.
    pub blend: Option<wgpu::BlendState>,
}

impl ColorTarget {
    /// The colour target `target`, every channel written.
    pub fn new(target: TargetName) -> Self {
        Self {
            target,
            write_mask: wgpu::ColorWrites::ALL,
            blend: None,
        }
    }
    /// A target nothing is written to.
    pub fn masked(target: TargetName) -> Self {
        Self {
            target,
            write_mask: wgpu::ColorWrites::empty(),
            blend: None,
        }
    }
}

/// The depth target of a render program.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct DepthTarget {
    /// The depth slot or scratch texture.
    pub target: TargetName,
    /// The depth test; a fragment that fails it is dropped.
    pub compare: wgpu::CompareFunction,
    /// Whether passing fragments write their depth; false tests against a prepass's depth.
    pub write: bool,
}

/// How primitives are assembled and rasterised.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Primitive {
    /// How vertices form primitives; triangle list by default.
    pub topology: wgpu::PrimitiveTopology,
    /// The face culled; `None` (the default) draws both.
    pub cull_mode: Option<wgpu::Face>,
    /// The winding that faces the viewer; counter-clockwise by default.
    pub front_face: wgpu::FrontFace,
    /// Keep depth unclipped (`DEPTH_CLIP_CONTROL`); ignored where the device lacks it, and
    /// the plan records that the pass asked for it as optional.
    pub unclipped_depth: bool,
}

impl Default for Primitive {
    fn default() -> Self {
        Self {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: None,
            front_face: wgpu::FrontFace::Ccw,
            unclipped_depth: false,
        }
    }
}

/// The stages before the fragment shader.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Geometry {
    /// A vertex shader; vertices come from storage buffers (no vertex buffers).
    Vertex {
        /// The vertex entry point.
        entry: &'static str,
    },
    /// A mesh shader, optionally fed by a task shader (`EXPERIMENTAL_MESH_SHADER`).
    Mesh {
        /// The task entry point, when a task shader launches the mesh workgroups.
        task: Option<&'static str>,
        /// The mesh entry point.
        mesh: &'static str,
    },
}

/// What kind of pipeline a program is.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum ProgramKind {
    Compute {
        entry: &'static str,
    },
    Render {
        geometry: Geometry,
        fragment: Option<&'static str>,
        targets: Vec<ColorTarget>,
        depth: Option<DepthTarget>,
        primitive: Primitive,
    },
}

/// A program as a pass declares it.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ProgramDesc {
    /// The pass's shader source the program is composed from.
    pub shader: &'static PassShader,
    /// Compute or render, with entry points and render state.
    pub kind: ProgramKind,
    /// Shader defs the program is composed with; programs that differ only here are
    /// separate pipelines.
    pub defs: Vec<(&'static str, ShaderDef)>,
    /// Bind groups 0, 1, … in order.
    pub layouts: Vec<BindingLayout>,
    /// Bytes of immediate data (push constants). Where the device has `IMMEDIATES` the
    /// shader is composed with `IMMEDIATES` defined and reads `var<immediate>`; elsewhere
    /// the graph appends one bind group holding a uniform block at binding 0, after the
    /// declared ones, and the shader reads that instead.
    pub immediate_size: u32,
}

impl ProgramDesc {
    /// A compute program running `entry` of `shader`.
    pub fn compute(shader: &'static PassShader, entry: &'static str) -> Self {
        Self {
            shader,
            kind: ProgramKind::Compute { entry },
            defs: Vec::new(),
            layouts: Vec::new(),
            immediate_size: 0,
        }
    }
    /// A vertex + fragment program with no targets yet.
    pub fn render(shader: &'static PassShader, vertex: &'static str) -> Self {
        Self::with_geometry(shader, Geometry::Vertex { entry: vertex })
    }
    /// A mesh (+ task) + fragment program.
    pub fn mesh(
        shader: &'static PassShader,
        task: Option<&'static str>,
        mesh: &'static str,
    ) -> Self {
        Self::with_geometry(shader, Geometry::Mesh { task, mesh })
    }
    fn with_geometry(shader: &'static PassShader, geometry: Geometry) -> Self {
        Self {
            shader,
            kind: ProgramKind::Render {
                geometry,
                fragment: None,
                targets: Vec::new(),
                depth: None,
                primitive: Primitive::default(),
            },
            defs: Vec::new(),
            layouts: Vec::new(),
            immediate_size: 0,
        }
    }
    /// Adds shader defs; a def set again replaces the earlier value.
    pub fn defs(mut self, defs: &impl ShaderDefs) -> Self {
        for (name, value) in defs.shader_defs() {
            self.defs.retain(|(n, _)| *n != name);
            self.defs.push((name, value));
        }
        self
    }
    /// Adds the next bind group's layout.
    pub fn layout(mut self, layout: BindingLayout) -> Self {
        self.layouts.push(layout);
        self
    }
    /// Sets the bytes of immediate data (see [`ProgramDesc::immediate_size`]).
    pub fn immediates(mut self, bytes: u32) -> Self {
        self.immediate_size = bytes;
        self
    }
    fn render_mut(&mut self) -> Option<&mut ProgramKind> {
        match &mut self.kind {
            k @ ProgramKind::Render { .. } => Some(k),
            ProgramKind::Compute { .. } => None,
        }
    }
    /// Sets the fragment entry point of a render program; ignored on a compute one.
    pub fn fragment(mut self, entry: &'static str) -> Self {
        if let Some(ProgramKind::Render { fragment, .. }) = self.render_mut() {
            *fragment = Some(entry);
        }
        self
    }
    /// Adds a colour target to a render program; ignored on a compute one.
    pub fn target(mut self, target: ColorTarget) -> Self {
        if let Some(ProgramKind::Render { targets, .. }) = self.render_mut() {
            targets.push(target);
        }
        self
    }
    /// Sets the depth target of a render program; ignored on a compute one.
    pub fn depth(mut self, depth: DepthTarget) -> Self {
        if let Some(ProgramKind::Render { depth: d, .. }) = self.render_mut() {
            *d = Some(depth);
        }
        self
    }
    /// Sets primitive assembly of a render program; ignored on a compute one.
    pub fn primitive(mut self, primitive: Primitive) -> Self {
        if let Some(ProgramKind::Render { primitive: p, .. }) = self.render_mut() {
            *p = primitive;
        }
        self
    }

    /// The entry points, in pipeline order, for dumps.
    pub fn entries(&self) -> Vec<&'static str> {
        match &self.kind {
            ProgramKind::Compute { entry } => vec![entry],
            ProgramKind::Render {
                geometry, fragment, ..
            } => {
                let mut v = match geometry {
                    Geometry::Vertex { entry } => vec![*entry],
                    Geometry::Mesh { task, mesh } => task.iter().copied().chain([*mesh]).collect(),
                };
                v.extend(fragment.iter().copied());
                v
            }
        }
    }
    /// `compute`, `render` or `mesh`, for dumps.
    pub fn kind_name(&self) -> &'static str {
        match &self.kind {
            ProgramKind::Compute { .. } => "compute",
            ProgramKind::Render {
                geometry: Geometry::Vertex { .. },
                ..
            } => "render",
            ProgramKind::Render {
                geometry: Geometry::Mesh { .. },
                ..
            } => "mesh",
        }
    }
    /// Device features the program cannot run without.
    pub fn required_features(&self) -> wgpu::Features {
        match &self.kind {
            ProgramKind::Render {
                geometry: Geometry::Mesh { .. },
                ..
            } => wgpu::Features::EXPERIMENTAL_MESH_SHADER,
            _ => wgpu::Features::empty(),
        }
    }
}

/// A declared program as the plan records it.
#[derive(Clone, Debug, Serialize)]
pub struct ProgramPlan {
    pub name: String,
    pub kind: &'static str,
    pub shader: &'static str,
    pub entries: Vec<&'static str>,
    pub defs: Vec<(String, String)>,
    pub immediate_size: u32,
}

impl ProgramPlan {
    pub(crate) fn new(name: &str, desc: &ProgramDesc) -> Self {
        Self {
            name: name.to_string(),
            kind: desc.kind_name(),
            shader: desc.shader.name,
            entries: desc.entries(),
            defs: desc
                .defs
                .iter()
                .map(|(n, v)| (n.to_string(), format!("{v:?}")))
                .collect(),
            immediate_size: desc.immediate_size,
        }
    }
}
