//! The reference: depth.wgsl and shade.wgsl step by step on the CPU, in f32 and in the
//! same order, so the GPU test can hold the pass to exact results where the shader's
//! arithmetic is exact (ids, depths) and to a stated tolerance where drivers may round
//! differently (the shaded view).

use crate::brdf::Surface;
use crate::settings::{DebugView, Settings};
use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use meshlight_gpu_scene::SceneData;
use meshlight_gpu_scene::surface::{
    barycentrics, interpolated_uv, transformed_uv, triangle_corners, uv_transform_rows,
};
use meshlight_gpu_scene::texture::{sample_texture, texture_lod};
use meshlight_scene::asset::format::MeshletRecord;
use meshlight_shaders::cpu::layout::{
    Cluster, ClusterGrid, ClusterableKind, ClusterableObject, Instance, MAP_BASE_COLOR,
    MAP_EMISSIVE, MAP_METALLIC_ROUGHNESS, MAP_NORMAL, MAP_OCCLUSION, MATERIAL_FLAG_CHECKER,
    MATERIAL_FLAG_DOUBLE_SIDED, MESH_FLAG_COLORS, Material, TextureRef, View, material_uv,
};
use meshlight_shaders::cpu::light::{cluster_index, z_slice_of_depth};
use meshlight_shaders::cpu::visbuffer;

/// shade.wgsl's `SKY_ZENITH`: the colour of an empty pixel at the top of the screen.
pub const SKY_ZENITH: Vec3 = Vec3::new(0.25, 0.45, 0.8);
/// shade.wgsl's `SKY_HORIZON`: the colour of an empty pixel at the bottom, where the
/// gradient starts.
pub const SKY_HORIZON: Vec3 = Vec3::new(0.75, 0.85, 0.95);
/// The `raster` view's colour of a software-rasterised cluster (`SOFTWARE_COLOR`).
pub const SOFTWARE_COLOR: [u8; 3] = [230, 90, 50];
/// The `raster` view's colour of a hardware-rasterised cluster.
pub const HARDWARE_COLOR: [u8; 3] = [50, 120, 230];
/// Dark checker squares multiply the base colour by this (`CHECKER_DARK`).
pub const CHECKER_DARK: f32 = 0.55;

/// Everything the pass reads, as the CPU holds it.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    /// The scene the visibility ids refer into.
    pub scene: &'a SceneData,
    /// The camera the frame was drawn with.
    pub view: &'a View,
    /// The slots visibility cluster ids index.
    pub raster_clusters: &'a [Cluster],
    /// `raster_counts[0]`: ids below it were drawn by the software rasteriser.
    pub software_clusters: u32,
    /// `width × height` values, row-major.
    pub visbuffer: &'a [u64],
    /// Columns of the visibility buffer and the image.
    pub width: u32,
    /// Rows of the visibility buffer and the image.
    pub height: u32,
    /// Light clustering's output, when the frame has it.
    pub lights: Option<ClusteredLights<'a>>,
    /// The `pyramid` slot's mips, finest first, when the frame binds one.
    pub pyramid: Option<&'a [PyramidMip]>,
    /// The `second_counts` slot (the second culling pass's `raster_counts`), if bound.
    pub second_counts: Option<&'a [u32]>,
    /// The `occluded_per_instance` slot, if bound: `[2i]` cut, `[2i + 1]` left hidden.
    pub occluded_per_instance: Option<&'a [u32]>,
    /// The `stream_errors` slot, if bound: per group, its error while its page is not
    /// in the streaming pool, else 0.
    pub stream_errors: Option<&'a [f32]>,
    /// The sun's shadow cascades, when the frame binds them.
    pub shadows: Option<crate::shadows::ShadowFrame<'a>>,
}

/// The `residency` view's colours: at the wanted level, then one, two, three or more
/// levels coarser (shade.wgsl's `RESIDENCY_COLORS`).
pub const RESIDENCY_COLORS: [Vec3; 4] = [
    Vec3::new(0.3, 0.8, 0.35),
    Vec3::new(0.95, 0.85, 0.2),
    Vec3::new(1.0, 0.5, 0.1),
    Vec3::new(0.95, 0.15, 0.1),
];

/// shade.wgsl's `levels_missing`: how many levels (at most 3) coarser than the view
/// wants `cluster` is drawn because its source group's page is missing: its missing
/// error projected on the meshlet's bounds, against the threshold, a level per doubling.
pub fn levels_missing(
    scene: &SceneData,
    view: &View,
    stream_errors: Option<&[f32]>,
    cluster: &Cluster,
    lod_threshold_px: f32,
) -> u32 {
    use meshlight_shaders::cpu::lod::{
        error_perceptible, instance_max_scale, project_error_to_pixels,
    };
    let Some(errors) = stream_errors else {
        return 0;
    };
    let m = meshlet_of(scene, cluster);
    let Some(&missing) = errors.get(m.source_group as usize) else {
        return 0;
    };
    if missing <= 0.0 {
        return 0;
    }
    let instance = instance_of(scene, cluster);
    let scale = instance_max_scale(&instance.world_from_local);
    let world = Mat4::from_cols_array_2d(&instance.world_from_local);
    let centre = world * Vec4::new(m.bounds[0], m.bounds[1], m.bounds[2], 1.0);
    let px = project_error_to_pixels(
        view,
        centre.truncate().to_array(),
        m.bounds[3] * scale,
        missing * scale,
    );
    if !error_perceptible(px, lod_threshold_px) {
        return 0;
    }
    1 + (px / lod_threshold_px).log2().floor().min(2.0) as u32
}

/// The `occlusion` view's colour of a cluster the first pass drew. This and the three
/// below mirror shade.wgsl's constants of the same names.
pub const FIRST_PASS_COLOR: Vec3 = Vec3::new(0.35, 0.85, 0.4);
/// The `occlusion` view's colour of a cluster the second pass drew.
pub const SECOND_PASS_COLOR: Vec3 = Vec3::new(0.3, 0.55, 1.0);
/// The colour an instance wholly culled by occlusion tends to.
pub const CULLED_COLOR: Vec3 = Vec3::new(1.0, 0.2, 0.15);
/// How far towards `CULLED_COLOR` a wholly culled instance goes.
pub const CULLED_TINT: f32 = 0.7;

/// shade.wgsl's `drawn_by_second_pass`: slot `id` lies between the first pass's
/// software and hardware clusters, where the second pass writes (`[7] <= id < [3]`).
pub fn drawn_by_second_pass(second_counts: Option<&[u32]>, id: u32) -> bool {
    second_counts.is_some_and(|c| id >= c[7] && id < c[3])
}

/// shade.wgsl's `culled_share`: left hidden / cut of `instance`, 0 when unknown.
pub fn culled_share(occluded_per_instance: Option<&[u32]>, instance: u32) -> f32 {
    let Some(words) = occluded_per_instance else {
        return 0.0;
    };
    let at = instance as usize * 2;
    if at + 1 >= words.len() || words[at] == 0 {
        return 0.0;
    }
    words[at + 1].min(words[at]) as f32 / words[at] as f32
}

/// The `occlusion` view's colour of a covered pixel before the clamp: the pass colour,
/// tinted towards red by the culled share, times `0.45 + 0.55 · min(luma(shaded), 1)`.
pub fn occlusion_color(second_pass: bool, culled_share: f32, shaded: Vec3) -> Vec3 {
    let base = if second_pass {
        SECOND_PASS_COLOR
    } else {
        FIRST_PASS_COLOR
    };
    let tint = mix(base, CULLED_COLOR, CULLED_TINT * culled_share);
    let lit = shaded.dot(Vec3::new(0.2126, 0.7152, 0.0722)).min(1.0);
    tint * (0.45 + 0.55 * lit)
}

/// One mip of a depth pyramid as the texture holds it.
#[derive(Clone, Debug, PartialEq)]
pub struct PyramidMip {
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// `width × height` reverse-Z depths, row-major.
    pub texels: Vec<f32>,
}

/// shade.wgsl's `pyramid_depth`: the texel of mip `level` (clamped to the chain) that
/// covers `pixel`, `pixel >> (level + 1)` clamped to the mip's size.
pub fn pyramid_depth(mips: &[PyramidMip], pixel: [u32; 2], level: u32) -> f32 {
    let Some(last) = mips.len().checked_sub(1) else {
        return 0.0;
    };
    let mip = &mips[(level as usize).min(last)];
    let shift = (level as usize).min(last) as u32 + 1;
    let x = (pixel[0] >> shift).min(mip.width - 1);
    let y = (pixel[1] >> shift).min(mip.height - 1);
    mip.texels[(y * mip.width + x) as usize]
}

/// Light clustering's five outputs, as the pass binds them.
#[derive(Clone, Copy, Debug)]
pub struct ClusteredLights<'a> {
    /// The objects the lists index.
    pub objects: &'a [ClusterableObject],
    /// The froxel grid the lists were built over.
    pub grid: &'a ClusterGrid,
    /// Per froxel and kind: where its list starts.
    pub offsets: &'a [u32],
    /// Per froxel and kind: the length of its list.
    pub counts: &'a [u32],
    /// The lists back to back: indices into `objects`.
    pub list: &'a [u32],
}

/// The light-count view's hottest count (`LIGHT_COUNT_FULL`).
pub const LIGHT_COUNT_FULL: f32 = 32.0;

impl ClusteredLights<'_> {
    /// `froxel_list`: start and length of a pixel's (froxel, kind) list, clamped.
    fn froxel_list(&self, pixel: Vec2, view_z: f32, kind: u32) -> (u32, u32) {
        let g = self.grid;
        let tile = |i: usize| (((pixel[i] / g.tile_size[i]).max(0.0)) as u32).min(g.dims[i] - 1);
        let froxel = [tile(0), tile(1), z_slice_of_depth(g, view_z)];
        let at = (cluster_index(g, froxel) * ClusterableKind::COUNT + kind) as usize;
        if at >= self.offsets.len().min(self.counts.len()) {
            return (0, 0);
        }
        let len = self.list.len() as u32;
        let start = self.offsets[at].min(len);
        (start, self.counts[at].min(len - start))
    }

    /// `light_count`: point and spot lights of the pixel's froxel.
    fn light_count(&self, view: &View, pixel: Vec2, value: u64) -> u32 {
        let view_z = if is_empty(value) {
            3.4e38
        } else {
            view_z_from_depth(view, visbuffer::depth(value))
        };
        [ClusterableKind::PointLight, ClusterableKind::SpotLight]
            .map(|k| self.froxel_list(pixel, view_z, k as u32).1)
            .iter()
            .sum()
    }

    /// `clustered_lighting`: radiance from the point and spot lights of the froxel
    /// towards `v`, reflected by `s`.
    fn lighting(
        &self,
        view: &View,
        pixel: Vec2,
        depth: f32,
        s: &Surface,
        n: Vec3,
        v: Vec3,
    ) -> Vec3 {
        let uv = pixel * Vec2::from_array(view.inverse_viewport_size);
        let ndc = uv * Vec2::new(2.0, -2.0) + Vec2::new(-1.0, 1.0);
        let w = Mat4::from_cols_array_2d(&view.inverse_view_projection)
            * Vec4::new(ndc.x, ndc.y, depth, 1.0);
        let world = w.truncate() / w.w;
        let view_z = view_z_from_depth(view, depth);
        // In fixed point, as the shader sums (see `LIGHT_SUM_SCALE`).
        let mut sum = [0u32; 3];
        for kind in [ClusterableKind::PointLight, ClusterableKind::SpotLight] {
            let (start, len) = self.froxel_list(pixel, view_z, kind as u32);
            for &index in &self.list[start as usize..(start + len) as usize] {
                let light = &self.objects[index as usize];
                let [x, y, z, range] = light.position_range;
                let to_light = Vec3::new(x, y, z) - world;
                let d2 = to_light.dot(to_light).max(1e-4);
                let l = to_light / d2.sqrt();
                let ratio = d2 / (range * range).max(1e-8);
                let window = (1.0 - ratio * ratio).clamp(0.0, 1.0);
                let mut falloff = window * window / d2;
                if kind == ClusterableKind::SpotLight {
                    let [dx, dy, dz, cos_outer] = light.direction_cos_angle;
                    let cd = (-l).dot(Vec3::new(dx, dy, dz).normalize());
                    falloff *= smoothstep(cos_outer, cos_outer + (1.0 - cos_outer) * 0.2, cd);
                }
                let [r, g, b, intensity] = light.color_intensity;
                let c = Vec3::new(r, g, b) * intensity * falloff * s.light_response(n, v, l);
                let steps = c.clamp(Vec3::ZERO, Vec3::splat(LIGHT_SUM_MAX)) * LIGHT_SUM_SCALE
                    + Vec3::splat(0.5);
                for (acc, x) in sum.iter_mut().zip(steps.to_array()) {
                    *acc = acc.wrapping_add(x as u32);
                }
            }
        }
        Vec3::from_array(sum.map(|x| x as f32)) / LIGHT_SUM_SCALE
    }
}

/// shade.wgsl's fixed-point steps per unit of the clustered lights' sum, and the most
/// one light adds.
const LIGHT_SUM_SCALE: f32 = 65536.0;
const LIGHT_SUM_MAX: f32 = 64.0;

/// `view_z_from_depth`: the positive view-space distance of a reverse-Z depth.
fn view_z_from_depth(view: &View, depth: f32) -> f32 {
    let v = Mat4::from_cols_array_2d(&view.inverse_projection) * Vec4::new(0.0, 0.0, depth, 1.0);
    -v.z / v.w
}

/// WGSL's `smoothstep`.
fn smoothstep(edge0: f32, edge1: f32, x: f32) -> f32 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// shade.wgsl's `heat`: black through blue, green and yellow to red.
pub fn heat(t: f32) -> Vec3 {
    let x = t.clamp(0.0, 1.0);
    let band = |c: f32| (1.5 - (4.0 * x - c).abs()).clamp(0.0, 1.0);
    Vec3::new(band(3.0), band(2.0), band(1.0)) * (x * 8.0).min(1.0)
}

/// lowbias32, the hash of shade.wgsl's `hash`.
pub fn hash(x: u32) -> u32 {
    let mut h = x;
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^= h >> 16;
    h
}

/// The colour of an id in the debug views: three bytes of its hash lifted to 64..=255.
/// shade.wgsl's `cluster_key`: the scene cluster (instance, meshlet) as one word, so
/// its colour is the same whichever raster slot the atomics gave it this frame.
pub fn cluster_key(c: &Cluster) -> u32 {
    hash(c.instance) ^ c.meshlet
}

/// The colour a debug view gives an id: a hash of it, kept away from black (empty).
pub fn id_color(id: u32) -> [u8; 3] {
    let h = hash(id);
    [0, 8, 16].map(|shift| (64 + ((h >> shift) & 0xff) * 3 / 4) as u8)
}

/// The `depth` target: each pixel's reverse-Z depth, 0 where empty.
pub fn depth(visbuffer: &[u64], width: u32, height: u32) -> Vec<f32> {
    assert_eq!(
        visbuffer.len(),
        width as usize * height as usize,
        "the visibility buffer must hold width × height values"
    );
    visbuffer
        .iter()
        .map(|&v| {
            if is_empty(v) {
                0.0
            } else {
                visbuffer::depth(v)
            }
        })
        .collect()
}

/// The material a cluster's triangles take: its instance's plus its meshlet's slot.
pub fn material_of(scene: &SceneData, cluster: &Cluster) -> u32 {
    instance_of(scene, cluster)
        .material
        .wrapping_add(meshlet_of(scene, cluster).material())
}

/// The `material_depth` target: [`crate::material_depth`] of the material of the
/// cluster each pixel shows ([`material_of`]), 0 where empty.
pub fn material_depth(
    scene: &SceneData,
    raster_clusters: &[Cluster],
    visbuffer: &[u64],
) -> Vec<f32> {
    visbuffer
        .iter()
        .map(|&v| {
            if is_empty(v) {
                return 0.0;
            }
            let cluster = cluster_of(raster_clusters, v);
            crate::material_depth(material_of(scene, &cluster))
        })
        .collect()
}

/// The `color` target for `settings.view`, RGBA8 row-major, alpha 255.
pub fn shade(frame: &Frame, settings: &Settings) -> Vec<[u8; 4]> {
    let light = ShadeLight {
        direction: settings.light_direction.normalize_or_zero(),
        color: settings.light_color,
        ambient: settings.ambient_color,
        checker_scale: settings.checker_scale,
        pyramid_mip: settings.pyramid_mip,
        lod_threshold_px: settings.lod_threshold_px,
    };
    let mut out = Vec::with_capacity(frame.visbuffer.len());
    for y in 0..frame.height {
        for x in 0..frame.width {
            let value = frame.visbuffer[(y * frame.width + x) as usize];
            let rgb = pixel_color(frame, &light, settings.view, value, [x, y]);
            let [r, g, b] = rgb.clamp(Vec3::ZERO, Vec3::ONE).to_array().map(unorm8);
            out.push([r, g, b, 255]);
        }
    }
    out
}

/// The shader's `Params`: the light (direction already normalised) and the views'
/// settings.
struct ShadeLight {
    direction: Vec3,
    color: Vec3,
    ambient: Vec3,
    checker_scale: f32,
    pyramid_mip: u32,
    lod_threshold_px: f32,
}

/// shade.wgsl's `shade_pixels` before the clamp and the store.
fn pixel_color(
    frame: &Frame,
    light: &ShadeLight,
    view: DebugView,
    value: u64,
    at: [u32; 2],
) -> Vec3 {
    let pixel = Vec2::new(at[0] as f32, at[1] as f32) + Vec2::splat(0.5);
    let empty = is_empty(value);
    let id = visbuffer::cluster(value);
    match view {
        DebugView::LightCount => frame.lights.map_or(Vec3::ZERO, |lights| {
            heat(lights.light_count(frame.view, pixel, value) as f32 / LIGHT_COUNT_FULL)
        }),
        DebugView::Pyramid => frame.pyramid.map_or(Vec3::ZERO, |mips| {
            Vec3::splat(
                pyramid_depth(mips, at, light.pyramid_mip)
                    .max(0.0)
                    .sqrt()
                    .sqrt(),
            )
        }),
        _ if empty && view != DebugView::Shaded && view != DebugView::Depth => Vec3::ZERO,
        DebugView::Clusters => unorm(id_color(cluster_key(&cluster_of(
            frame.raster_clusters,
            value,
        )))),
        DebugView::Triangles => unorm(id_color(
            cluster_key(&cluster_of(frame.raster_clusters, value))
                .wrapping_mul(131)
                .wrapping_add(visbuffer::triangle(value)),
        )),
        DebugView::Lod => {
            let cluster = cluster_of(frame.raster_clusters, value);
            unorm(id_color(meshlet_of(frame.scene, &cluster).level()))
        }
        DebugView::Material => unorm(id_color(material_of(
            frame.scene,
            &cluster_of(frame.raster_clusters, value),
        ))),
        DebugView::Uv => {
            let uv = pixel_surface(frame, light.checker_scale, value, pixel).uv;
            (uv - uv.floor()).extend(0.0)
        }
        DebugView::Normal => {
            pixel_surface(frame, light.checker_scale, value, pixel).n * 0.5 + Vec3::splat(0.5)
        }
        DebugView::Mip => mip_color(&pixel_surface(frame, light.checker_scale, value, pixel)),
        DebugView::BaseColor => pixel_surface(frame, light.checker_scale, value, pixel)
            .base
            .truncate(),
        DebugView::Raster => unorm(if id < frame.software_clusters {
            SOFTWARE_COLOR
        } else {
            HARDWARE_COLOR
        }),
        // Reverse-Z depth falls off as 1 / distance; the fourth root spreads it.
        DebugView::Depth => Vec3::splat(visbuffer::depth(value).sqrt().sqrt()),
        DebugView::Shadow => frame.shadows.map_or(Vec3::ZERO, |shadows| {
            let p = pixel_surface(frame, light.checker_scale, value, pixel);
            crate::shadows::shadow_color(&shadows, frame.view, &p)
        }),
        DebugView::Residency => {
            let cluster = cluster_of(frame.raster_clusters, value);
            let levels = levels_missing(
                frame.scene,
                frame.view,
                frame.stream_errors,
                &cluster,
                light.lod_threshold_px,
            );
            let shaded = shade_surface(frame, light, value, pixel);
            let lit = shaded.dot(Vec3::new(0.2126, 0.7152, 0.0722)).min(1.0);
            RESIDENCY_COLORS[levels as usize] * (0.45 + 0.55 * lit)
        }
        DebugView::Occlusion => {
            let cluster = cluster_of(frame.raster_clusters, value);
            occlusion_color(
                drawn_by_second_pass(frame.second_counts, id),
                culled_share(frame.occluded_per_instance, cluster.instance),
                shade_surface(frame, light, value, pixel),
            )
        }
        DebugView::Shaded if empty => {
            let t = 1.0 - pixel.y / frame.height as f32;
            mix(SKY_HORIZON, SKY_ZENITH, t)
        }
        DebugView::Shaded => shade_surface(frame, light, value, pixel),
    }
}

/// GLSL's and WGSL's `mix`: `a · (1 − t) + b · t`.
fn mix(a: Vec3, b: Vec3, t: f32) -> Vec3 {
    a * (1.0 - t) + b * t
}

fn unorm(c: [u8; 3]) -> Vec3 {
    Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) / 255.0
}

/// A [0, 1] float to an 8-bit unorm, round to nearest.
fn unorm8(x: f32) -> u8 {
    (x * 255.0).round() as u8
}

/// The depth bits are 0 only for the cleared value (`visbuffer_is_empty`).
fn is_empty(value: u64) -> bool {
    value >> 32 == 0
}

/// `items[index]`, or zeros past the end, as robust buffer access reads on the GPU; the
/// rasterisers never write such ids.
fn read_or_zero<T: bytemuck::Zeroable + Copy>(items: &[T], index: u32) -> T {
    items.get(index as usize).copied().unwrap_or_else(T::zeroed)
}

fn cluster_of(raster_clusters: &[Cluster], value: u64) -> Cluster {
    read_or_zero(raster_clusters, visbuffer::cluster(value))
}

fn instance_of(scene: &SceneData, cluster: &Cluster) -> Instance {
    read_or_zero(&scene.instances, cluster.instance)
}

fn meshlet_of(scene: &SceneData, cluster: &Cluster) -> MeshletRecord {
    read_or_zero(&scene.meshlets, cluster.meshlet)
}

/// WGSL's `fract`: `x − floor(x)`, in [0, 1) for negative x too (unlike `f32::fract`).
fn fract(v: Vec2) -> Vec2 {
    v - v.floor()
}

/// shade.wgsl's `filtered_checker`: the square wave (1 on one colour of squares, 0 on
/// the other) averaged over the box `p ± w / 2`, `w` the larger footprint per axis.
pub fn filtered_checker(p: Vec2, ddx: Vec2, ddy: Vec2) -> f32 {
    let w = ddx.abs().max(ddy.abs()) + Vec2::splat(1e-4);
    let i = 2.0
        * ((fract((p - 0.5 * w) * 0.5) - Vec2::splat(0.5)).abs()
            - (fract((p + 0.5 * w) * 0.5) - Vec2::splat(0.5)).abs())
        / w;
    0.5 - 0.5 * i.x * i.y
}

/// `instance_transform_normal`: the transposed upper 3×3 of `local_from_world` (the
/// inverse transpose of `world_from_local`), then normalised.
pub fn transform_normal(instance: &Instance, n: Vec3) -> Vec3 {
    let m = Mat4::from_cols_array_2d(&instance.local_from_world);
    (Mat3::from_mat4(m).transpose() * n).normalize()
}

/// shade.wgsl's `PixelSurface`: what shading knows of a pixel before it is lit.
#[derive(Clone, Copy, Debug)]
pub struct PixelSurface {
    /// The pixel's material.
    pub material: Material,
    /// Base colour (factor × texture × checker) and alpha, linear.
    pub base: Vec4,
    /// Metalness after the metallic-roughness texture.
    pub metallic: f32,
    /// Roughness after the metallic-roughness texture.
    pub roughness: f32,
    /// Shading normal (normal map applied), world space.
    pub n: Vec3,
    /// Direction to the eye.
    pub v: Vec3,
    /// The surface point, world space.
    pub world: Vec3,
    /// The ambient light's share the occlusion map leaves.
    pub occlusion: f32,
    /// Emitted light after the emissive texture.
    pub emissive: Vec3,
    /// Texture coordinates at the pixel centre.
    pub uv: Vec2,
    /// Their change per pixel step in x.
    pub uv_dx: Vec2,
    /// ... and in y.
    pub uv_dy: Vec2,
}

impl PixelSurface {
    /// shade.wgsl's `sample_map`: `map` at the pixel, or `fallback` without a texture.
    fn sample_map(&self, textures: &[u32], map: usize, fallback: Vec4) -> Vec4 {
        match TextureRef::from_words(self.material.maps[map]) {
            Some(t) => sample_texture(textures, &t, self.uv, self.uv_dx, self.uv_dy),
            None => fallback,
        }
    }
}

/// shade.wgsl's `mapped_normal`: the normal map's texel in the triangle's tangent frame.
pub fn mapped_normal(n: Vec3, world: [Vec3; 3], uv: [Vec2; 3], texel: Vec3, scale: f32) -> Vec3 {
    let (e1, e2) = (world[1] - world[0], world[2] - world[0]);
    let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
    let r = d1.x * d2.y - d2.x * d1.y;
    let t_raw = (e1 * d2.y - e2 * d1.y) * wgsl_sign(r);
    let t_perp = t_raw - n * n.dot(t_raw);
    if r == 0.0 || t_perp.dot(t_perp) < 1e-20 {
        return n;
    }
    let t = t_perp.normalize();
    let b = n.cross(t) * -wgsl_sign(r);
    let m = (texel * 2.0 - Vec3::ONE) * Vec3::new(scale, scale, 1.0);
    (t * m.x + b * m.y + n * m.z).normalize()
}

/// WGSL's `sign`: 0 for 0 (Rust's `signum` gives 1).
fn wgsl_sign(x: f32) -> f32 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// shade.wgsl's `pixel_surface`: the pixel's triangle, its material and its textures.
pub fn pixel_surface(frame: &Frame, checker_scale: f32, value: u64, pixel: Vec2) -> PixelSurface {
    let scene = frame.scene;
    let cluster = cluster_of(frame.raster_clusters, value);
    let instance = instance_of(scene, &cluster);
    let m = meshlet_of(scene, &cluster);
    let mesh = scene
        .meshes
        .get(instance.mesh as usize)
        .copied()
        .unwrap_or_default();
    let corners = triangle_corners(scene, &mesh, &m, visbuffer::triangle(value));
    let world_from_local = Mat4::from_cols_array_2d(&instance.world_from_local);
    let view_projection = Mat4::from_cols_array_2d(&frame.view.view_projection);
    let world = corners.map(|c| (world_from_local * c.position.extend(1.0)).truncate());
    let clip = world.map(|w| view_projection * w.extend(1.0));
    let size = Vec2::new(frame.width as f32, frame.height as f32);
    let bary = barycentrics(clip, pixel, size);
    let b = bary.b;
    let [k0, k1, k2] = corners;
    let material = scene
        .materials
        .get(instance.material as usize + m.material() as usize)
        .copied()
        .unwrap_or_default();
    let mut uv = corners.map(|c| c.uv);
    let camera = Vec3::from_array(frame.view.camera_position);
    let point = world[0] * b.x + world[1] * b.y + world[2] * b.z;
    let mut at = interpolated_uv(uv, &bary);
    if material.uv_transform != 0 {
        // The coordinates the maps are sampled at, and the corners' for the normal
        // map's tangent frame, as shade.wgsl transforms them.
        let r = uv_transform_rows(&scene.textures, material.uv_transform);
        at = transformed_uv(&r, at);
        uv = uv.map(|c| Vec2::from(material_uv(&r, c.to_array())));
    }
    let mut s = PixelSurface {
        material,
        base: Vec4::ONE,
        metallic: 0.0,
        roughness: 0.0,
        n: transform_normal(
            &instance,
            k0.normal * b.x + k1.normal * b.y + k2.normal * b.z,
        )
        .normalize(),
        v: (camera - point).normalize(),
        world: point,
        occlusion: 1.0,
        emissive: Vec3::ZERO,
        uv: at.uv,
        uv_dx: at.dx,
        uv_dy: at.dy,
    };
    let textures = &scene.textures;
    s.base =
        Vec4::from_array(material.base_color) * s.sample_map(textures, MAP_BASE_COLOR, Vec4::ONE);
    if mesh.flags & MESH_FLAG_COLORS != 0 {
        s.base *= k0.color * b.x + k1.color * b.y + k2.color * b.z;
    }
    if material.flags & MATERIAL_FLAG_CHECKER != 0 {
        let scale = checker_scale;
        let checker = filtered_checker(s.uv * scale, s.uv_dx * scale, s.uv_dy * scale);
        s.base = (s.base.truncate() * (CHECKER_DARK * (1.0 - checker) + checker)).extend(s.base.w);
    }
    let metallic_roughness = s.sample_map(textures, MAP_METALLIC_ROUGHNESS, Vec4::ONE);
    s.metallic = material.metallic * metallic_roughness.z;
    s.roughness = material.roughness * metallic_roughness.y;
    if TextureRef::from_words(material.maps[MAP_NORMAL]).is_some() {
        let texel = s.sample_map(textures, MAP_NORMAL, Vec4::new(0.5, 0.5, 1.0, 1.0));
        s.n = mapped_normal(s.n, world, uv, texel.truncate(), material.emissive[3]);
    }
    let xyw = |c: Vec4| Vec3::new(c.x, c.y, c.w);
    let back = Mat3::from_cols(xyw(clip[0]), xyw(clip[1]), xyw(clip[2])).determinant() < 0.0;
    if material.flags & MATERIAL_FLAG_DOUBLE_SIDED != 0 && back {
        s.n = -s.n;
    }
    s.occlusion = 1.0
        + material.occlusion_strength * (s.sample_map(textures, MAP_OCCLUSION, Vec4::ONE).x - 1.0);
    s.emissive = Vec4::from_array(material.emissive).truncate()
        * s.sample_map(textures, MAP_EMISSIVE, Vec4::ONE).truncate();
    s
}

/// shade.wgsl's `shade`: the pixel's surface lit through its material (resolve::brdf).
fn shade_surface(frame: &Frame, light: &ShadeLight, value: u64, pixel: Vec2) -> Vec3 {
    let p = pixel_surface(frame, light.checker_scale, value, pixel);
    let s = Surface::new(p.base.truncate(), p.metallic, p.roughness);
    let mut sun = light.color * s.light_response(p.n, p.v, light.direction);
    if let Some(shadows) = &frame.shadows {
        sun *= crate::shadows::shadow_factor(shadows, frame.view, p.world, p.n);
    }
    let mut radiance = light.ambient * s.ambient_response() * p.occlusion + sun;
    if let Some(lights) = frame.lights {
        radiance += lights.lighting(frame.view, pixel, visbuffer::depth(value), &s, p.n, p.v);
    }
    radiance + p.emissive
}

/// shade.wgsl's `mip_color`: a colour per level the base colour texture is read at.
fn mip_color(p: &PixelSurface) -> Vec3 {
    match TextureRef::from_words(p.material.maps[MAP_BASE_COLOR]) {
        Some(t) => unorm(id_color(texture_lod(&t, p.uv_dx, p.uv_dy).floor() as u32)),
        None => Vec3::ZERO,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clip_of(ndc: Vec2, w: f32) -> Vec4 {
        Vec4::new(ndc.x * w, ndc.y * w, 0.5, w)
    }

    fn pixel_of(ndc: Vec2, size: Vec2) -> Vec2 {
        Vec2::new((ndc.x + 1.0) * 0.5 * size.x, (1.0 - ndc.y) * 0.5 * size.y)
    }

    #[test]
    fn id_colours_are_lifted_hash_bytes() {
        // lowbias32 of 1, computed by hand from the constants.
        let mut h: u32 = 1;
        h ^= h >> 16;
        h = h.wrapping_mul(0x7feb352d);
        h ^= h >> 15;
        h = h.wrapping_mul(0x846ca68b);
        h ^= h >> 16;
        assert_eq!(hash(1), h);
        assert_ne!(hash(1), hash(2));
        let c = id_color(1);
        assert_eq!(c[0] as u32, 64 + (h & 0xff) * 3 / 4);
        assert_eq!(c[2] as u32, 64 + ((h >> 16) & 0xff) * 3 / 4);
        for id in 0..1000 {
            assert!(id_color(id).iter().all(|&b| b >= 64));
        }
        // Neighbouring ids get visibly different colours.
        let far = (0..200u32)
            .filter(|&i| {
                let (a, b) = (id_color(i), id_color(i + 1));
                (0..3).map(|k| a[k].abs_diff(b[k]) as u32).sum::<u32>() > 30
            })
            .count();
        assert!(far > 180, "{far}");
    }

    #[test]
    fn barycentrics_are_perspective_correct_and_their_derivatives_match_differences() {
        let size = Vec2::new(64.0, 48.0);
        let ndc = [
            Vec2::new(-0.8, -0.6),
            Vec2::new(0.7, -0.5),
            Vec2::new(0.1, 0.9),
        ];
        let w = [1.0, 3.0, 7.0];
        let clip = [0, 1, 2].map(|i| clip_of(ndc[i], w[i]));
        // At a corner the weights are that corner's.
        for (i, unit) in [Vec3::X, Vec3::Y, Vec3::Z].into_iter().enumerate() {
            let b = barycentrics(clip, pixel_of(ndc[i], size), size).b;
            assert!((b - unit).abs().max_element() < 1e-4, "{i}: {b}");
        }
        // The screen midpoint of a far and a near corner lies nearer the near one in
        // 3-D: weights w_far / (w_near + w_far) for the near corner.
        let mid = (ndc[0] + ndc[2]) * 0.5;
        let b = barycentrics(clip, pixel_of(mid, size), size).b;
        let want = Vec3::new(7.0 / 8.0, 0.0, 1.0 / 8.0);
        assert!((b - want).abs().max_element() < 1e-5, "{b}");
        // Derivatives against central differences of the weights.
        let p = pixel_of(Vec2::new(0.0, -0.1), size);
        let at = |q: Vec2| barycentrics(clip, q, size).b;
        let got = barycentrics(clip, p, size);
        let dx = (at(p + Vec2::X * 0.01) - at(p - Vec2::X * 0.01)) / 0.02;
        let dy = (at(p + Vec2::Y * 0.01) - at(p - Vec2::Y * 0.01)) / 0.02;
        assert!(
            (got.ddx - dx).abs().max_element() < 1e-3,
            "{} vs {dx}",
            got.ddx
        );
        assert!(
            (got.ddy - dy).abs().max_element() < 1e-3,
            "{} vs {dy}",
            got.ddy
        );
        assert!(got.ddx.abs().max_element() > 1e-3 && got.ddy.abs().max_element() > 1e-3);
        // Weights always sum to 1; a degenerate triangle falls back to corner 0.
        assert!((got.b.element_sum() - 1.0).abs() < 1e-6);
        let flat = [clip[0], clip[0], clip[1]];
        assert_eq!(barycentrics(flat, p, size).b, Vec3::X);
    }

    #[test]
    fn the_checker_is_a_square_wave_that_fades_to_grey_when_filtered() {
        let tiny = Vec2::splat(1e-6);
        // Squares of one unit: (0.5, 0.5) and (1.5, 1.5) are one colour, (1.5, 0.5) the other.
        let a = filtered_checker(Vec2::new(0.5, 0.5), tiny, tiny);
        let b = filtered_checker(Vec2::new(1.5, 1.5), tiny, tiny);
        let c = filtered_checker(Vec2::new(1.5, 0.5), tiny, tiny);
        let d = filtered_checker(Vec2::new(-0.5, 0.5), tiny, tiny);
        assert!((a - b).abs() < 1e-2 && (a - c).abs() > 0.98, "{a} {b} {c}");
        assert!(
            (c - d).abs() < 1e-2,
            "negative coordinates continue the pattern"
        );
        // A footprint of many squares averages to half.
        let wide = Vec2::splat(20.0);
        assert!((filtered_checker(Vec2::new(0.3, 0.7), wide, wide) - 0.5).abs() < 0.05);
    }

    #[test]
    fn normals_use_the_inverse_transpose() {
        // A non-uniform scale: the plane x = y through the origin has normal (1, -1, 0)
        // before; after stretching x by 2 the plane is x = 2y, normal (1, -2, 0).
        let world_from_local = Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0));
        let instance = Instance {
            world_from_local: world_from_local.to_cols_array_2d(),
            local_from_world: world_from_local.inverse().to_cols_array_2d(),
            ..Default::default()
        };
        let n = transform_normal(&instance, Vec3::new(1.0, -1.0, 0.0).normalize());
        let want = Vec3::new(1.0, -2.0, 0.0).normalize();
        assert!((n - want).length() < 1e-6, "{n}");
    }
}
