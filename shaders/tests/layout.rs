//! The Rust mirrors in `cpu::layout` have exactly the member offsets and sizes naga
//! computes for the WGSL structs, so buffers uploaded with bytemuck read back correctly.

use std::mem::{offset_of, size_of};

use meshlight_shaders::cpu::layout::{
    Cluster, ClusterGrid, ClusterableObject, Instance, Material, Mesh, View,
};
use meshlight_shaders::{Capabilities, PassShader, ShaderLibrary, pass_shader};

const STRUCTS: PassShader = pass_shader!("layout", "wgsl/uses_every_module.wgsl");

/// (member name, offset) of the WGSL struct whose name starts with `name`, and its size.
fn wgsl_layout(module: &naga::Module, name: &str) -> (Vec<(String, u32)>, u32) {
    let decorated = |ty_name: &str| {
        // naga_oil appends a module decoration to imported names.
        ty_name == name
            || ty_name
                .strip_prefix(name)
                .is_some_and(|rest| rest.starts_with("X_naga_oil"))
    };
    let ty = module
        .types
        .iter()
        .map(|(_, ty)| ty)
        .find(|ty| ty.name.as_deref().is_some_and(decorated))
        .unwrap_or_else(|| panic!("struct {name} not in the composed module"));
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("{name} is not a struct");
    };
    let members = members
        .iter()
        .map(|m| (m.name.clone().unwrap(), m.offset))
        .collect();
    (members, *span)
}

macro_rules! assert_layout {
    ($module:expr, $wgsl:literal, $rust:ty, [$($field:ident),* $(,)?]) => {{
        let (members, size) = wgsl_layout($module, $wgsl);
        let rust: Vec<(String, u32)> =
            vec![$((stringify!($field).to_owned(), offset_of!($rust, $field) as u32)),*];
        assert_eq!(members, rust, "member offsets of {} differ from the WGSL", stringify!($rust));
        assert_eq!(size, size_of::<$rust>() as u32, "size of {} differs from the WGSL", stringify!($rust));
    }};
}

#[test]
fn rust_mirrors_match_the_wgsl_layouts() {
    let module = ShaderLibrary::new(Capabilities::empty())
        .unwrap()
        .compose(&STRUCTS, &[])
        .unwrap_or_else(|error| panic!("{error}"));
    assert_layout!(
        &module,
        "View",
        View,
        [
            view,
            projection,
            view_projection,
            inverse_view,
            inverse_projection,
            inverse_view_projection,
            previous_view_projection,
            frustum,
            camera_position,
            near,
            viewport_size,
            inverse_viewport_size,
            lod_scale,
            frame_index,
            orthographic,
            padding,
        ]
    );
    assert_layout!(
        &module,
        "Mesh",
        Mesh,
        [
            position_grid,
            uv_grid,
            bounding_sphere,
            first_meshlet,
            meshlet_count,
            flags,
            level_count,
        ]
    );
    assert_layout!(
        &module,
        "Material",
        Material,
        [
            base_color,
            emissive,
            metallic,
            roughness,
            occlusion_strength,
            alpha_cutoff,
            flags,
            uv_transform,
            maps,
        ]
    );
    assert_layout!(&module, "Cluster", Cluster, [instance, meshlet]);
    assert_layout!(
        &module,
        "Instance",
        Instance,
        [
            world_from_local,
            previous_world_from_local,
            local_from_world,
            position_grid,
            material,
            first_meshlet,
            meshlet_count,
            mesh,
        ]
    );
    assert_layout!(
        &module,
        "ClusterableObject",
        ClusterableObject,
        [
            position_range,
            direction_cos_angle,
            color_intensity,
            kind,
            sin_angle,
            payload,
            padding,
        ]
    );
    assert_layout!(
        &module,
        "ClusterGrid",
        ClusterGrid,
        [
            dims,
            cluster_count,
            tile_size,
            near,
            far,
            z_slice_scale,
            z_slice_bias,
            padding,
        ]
    );
}
