//! Scenes the command line, the examples and the benchmarks draw: meshes loaded (baked
//! once and cached, or read from an asset file) and instances placed.

use crate::streaming::PageSource;
use glam::{Mat4, Quat, Vec3};
use meshlight::gpu_scene::lattice::Lattice;
use meshlight::gpu_scene::{Camera, Material, MeshId, SceneData};
use meshlight::scene::asset::format;
use meshlight::scene::cache::{self, Source};
use meshlight::scene::load::{ObjMaterial, load_obj_scene, names_material_library};
use meshlight::scene::{BuildOptions, MeshletAsset, SceneError, Terrain, build_asset};
use meshlight::shaders::cpu::layout::{ClusterableKind, ClusterableObject, TextureWrap};
use std::path::Path;
use std::sync::Mutex;

/// Instances of the default scene: with the 1,048,576-triangle procedural mesh, a little
/// over 10^9 source triangles.
pub const DEFAULT_INSTANCES: u32 = 1024;
/// Point lights of the default scene ([`field_lights`]).
pub const DEFAULT_LIGHTS: u32 = 256;

/// The asset of a mesh argument: `procedural` (the default mesh with `segments`), a
/// baked `.mlasset` file, or a mesh file baked on first use and cached (keyed by the
/// file's bytes and the bake options), its progress logged while it bakes.
pub fn load_asset(mesh: &Path, segments: u32) -> Result<MeshletAsset, SceneError> {
    open_asset(mesh, segments, false)
}

/// [`load_asset`], and with `streamed` the asset opened for streaming
/// ([`MeshletAsset::open_resident`]): a baked `.mlasset` file, or the cache's file of a
/// mesh baked on first use (baked into the cache first when it is not there): only its
/// resident part is read, its pages when the view needs them.
pub fn open_asset(mesh: &Path, segments: u32, streamed: bool) -> Result<MeshletAsset, SceneError> {
    if mesh.extension().is_some_and(|e| e == "mlasset") {
        // Every check `meshlight inspect` runs, so nothing it rejects reaches the GPU
        // (a streamed asset's pages are checked as they are read).
        return match streamed {
            true => MeshletAsset::open_resident(mesh),
            false => MeshletAsset::load_verified(mesh),
        };
    }
    let source = if mesh.as_os_str() == "procedural" {
        Source::Procedural { segments }
    } else {
        Source::File(mesh.to_path_buf())
    };
    let name = source.name();
    let open = match streamed {
        true => cache::open_or_bake_resident,
        false => cache::load_or_bake,
    };
    let (asset, _) = open(
        &source,
        &BuildOptions::default(),
        &cache::cache_dir(),
        &mut |p| cache::log_progress(&name, p),
    )?;
    Ok(asset)
}

/// An OBJ mesh argument whose `.mtl` gives it materials: the asset baked with a slot per
/// material (cached by content, as a glTF scene's meshes are) and the materials. `None`
/// for any other mesh argument, and for an OBJ without usable materials (which
/// [`load_asset`] bakes as before).
pub fn load_obj_with_materials(
    mesh: &Path,
) -> Result<Option<(MeshletAsset, Vec<ObjMaterial>)>, SceneError> {
    open_obj_with_materials(mesh, false)
}

/// [`load_obj_with_materials`], and with `streamed` the cached asset opened for
/// streaming (its resident part; its pages read from the cache's file).
pub fn open_obj_with_materials(
    mesh: &Path,
    streamed: bool,
) -> Result<Option<(MeshletAsset, Vec<ObjMaterial>)>, SceneError> {
    if !mesh
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
    {
        return Ok(None);
    }
    // An OBJ naming no material library bakes as before, so a cached asset is found
    // without parsing the file.
    let bytes = meshlight::scene::input::read_file(mesh, meshlight::scene::load::MAX_INPUT_BYTES)?;
    if !names_material_library(&bytes) {
        return Ok(None);
    }
    let scene = load_obj_scene(mesh)?;
    for w in &scene.warnings {
        log::warn!("{w}");
    }
    let plain = |m: &ObjMaterial| m.diffuse == [1.0; 3] && m.diffuse_texture.is_none();
    if scene.materials.iter().all(plain) {
        return Ok(None);
    }
    Ok(Some((cached_mesh(&scene.mesh, streamed)?, scene.materials)))
}

/// A mesh in memory (an OBJ's with its materials, a glTF scene's) baked once and cached
/// by content, its progress logged: whole, or with `streamed` the cache's file opened for
/// its resident part.
pub fn cached_mesh(
    mesh: &meshlight::scene::Mesh,
    streamed: bool,
) -> Result<MeshletAsset, SceneError> {
    let open = match streamed {
        true => cache::open_or_bake_mesh_resident,
        false => cache::load_or_bake_mesh,
    };
    let (asset, _) = open(
        mesh,
        &BuildOptions::default(),
        &cache::cache_dir(),
        &mut |p| cache::log_progress(&mesh.source, p),
    )?;
    Ok(asset)
}

/// `materials` added to `data` (textures included, repeating) as one run, one per
/// slot; returns the first.
pub fn add_obj_materials(
    data: &mut SceneData,
    materials: &[ObjMaterial],
) -> Result<u32, meshlight::gpu_scene::SceneDataError> {
    let first = data.materials.len() as u32;
    for m in materials {
        let mut maps = [None; meshlight::shaders::cpu::layout::MAP_COUNT];
        if let Some(image) = &m.diffuse_texture {
            maps[meshlight::shaders::cpu::layout::MAP_BASE_COLOR] =
                Some(data.add_image(image, true, [TextureWrap::Repeat; 2])?);
        }
        data.add_material(Material {
            base_color: m.diffuse,
            checker: false,
            maps,
            ..Material::default()
        })?;
    }
    Ok(first)
}

/// A small deterministic generator, so scenes are the same on every run.
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// A scene and the camera that frames it.
pub struct Placed {
    /// The meshes, materials and instances.
    pub data: SceneData,
    /// A camera that frames them.
    pub camera: Camera,
    /// Where each mesh's pages are read from, in mesh order, when `data` streams (see
    /// [`crate::Renderer::start_streaming`]); empty when it does not.
    pub sources: Vec<PageSource>,
}

/// Adds `asset` to `data` as mesh `name` and, when the scene streams, notes where its
/// pages come from ([`PageSource::of`]: its file when it was opened for streaming, else
/// the asset in memory).
fn add_mesh(
    data: &mut SceneData,
    sources: &mut Vec<PageSource>,
    name: &str,
    asset: &MeshletAsset,
) -> Result<MeshId, meshlight::gpu_scene::SceneDataError> {
    let mesh = data.add_mesh(name, asset)?;
    if data.streaming().is_some() {
        let source = PageSource::of(&std::sync::Arc::new(asset.clone())).map_err(|e| {
            meshlight::gpu_scene::SceneDataError::InvalidAsset {
                name: name.to_string(),
                reason: e.to_string(),
            }
        })?;
        sources.push(source);
    }
    Ok(mesh)
}

fn palette(data: &mut SceneData) -> Result<Vec<u32>, meshlight::gpu_scene::SceneDataError> {
    [
        [0.80, 0.34, 0.24],
        [0.86, 0.70, 0.30],
        [0.36, 0.62, 0.38],
        [0.30, 0.50, 0.78],
        [0.70, 0.70, 0.72],
        [0.58, 0.36, 0.66],
    ]
    .into_iter()
    .map(|base_color| {
        data.add_material(Material {
            base_color,
            ..Material::default()
        })
    })
    .collect()
}

/// The mesh a scene's copies share, its bounding radius and the palette they take turns
/// with: what every scene of many copies starts from.
struct Copies {
    mesh: MeshId,
    radius: f32,
    materials: Vec<u32>,
    /// The mesh's page source, in a streamed scene.
    sources: Vec<PageSource>,
}

/// What a scene's copies are painted with.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Paint {
    /// Six checkered colours, copy `i` in colour `i mod 6`: copies are told apart.
    Palette,
    /// The mesh's own materials, already in the scene: copy `i` takes the run (one
    /// material per slot of the mesh) starting at `runs[i mod runs.len()]`.
    Own(Vec<u32>),
}

impl Copies {
    /// The palette, then `asset` as mesh `mesh`, added to `data`.
    fn add(
        data: &mut SceneData,
        asset: &MeshletAsset,
    ) -> Result<Self, meshlight::gpu_scene::SceneDataError> {
        Self::add_painted(data, asset, Paint::Palette)
    }

    /// `asset` as mesh `mesh`, painted as `paint` says.
    fn add_painted(
        data: &mut SceneData,
        asset: &MeshletAsset,
        paint: Paint,
    ) -> Result<Self, meshlight::gpu_scene::SceneDataError> {
        let materials = match paint {
            Paint::Palette => palette(data)?,
            Paint::Own(runs) if !runs.is_empty() => runs,
            Paint::Own(_) => palette(data)?,
        };
        let mut sources = Vec::new();
        let mesh = add_mesh(data, &mut sources, "mesh", asset)?;
        let radius = mesh_radius(data, mesh);
        Ok(Self {
            mesh,
            radius,
            materials,
            sources,
        })
    }

    /// Copy `i` at `transform`, in the palette's colour for it.
    fn place(
        &self,
        data: &mut SceneData,
        i: usize,
        transform: Mat4,
    ) -> Result<(), meshlight::gpu_scene::SceneDataError> {
        let material = self.materials[i % self.materials.len()];
        data.add_instance(self.mesh, transform, material)?;
        Ok(())
    }
}

/// `instances` copies of `asset` standing on a field of hilly ground, each turned and
/// scaled a little, seen from a low camera at one corner looking across the field to
/// the horizon: near copies fill the screen, far ones shrink to a few pixels, so every
/// LOD level shows, and the hills hide some copies behind them.
///
/// The ground ([`field_ground`]) is one more mesh and instance, baked through the same
/// LOD DAG (cached like any bake) and added after the copies, so the copies keep mesh 0
/// and instances `0..instances`. An empty field has no ground either: the sky alone.
pub fn field(
    data: SceneData,
    asset: &MeshletAsset,
    instances: u32,
) -> Result<Placed, meshlight::gpu_scene::SceneDataError> {
    field_painted(data, asset, instances, Paint::Palette)
}

/// [`field`] with the copies painted as `paint` says.
pub fn field_painted(
    mut data: SceneData,
    asset: &MeshletAsset,
    instances: u32,
    paint: Paint,
) -> Result<Placed, meshlight::gpu_scene::SceneDataError> {
    let mut copies = Copies::add_painted(&mut data, asset, paint)?;
    let radius = copies.radius;
    let side = (instances as f32).sqrt().ceil().max(1.0) as u32;
    let spacing = radius * FIELD_SPACING;
    let ground = (instances > 0).then(|| field_ground(radius, instances));
    let ground_at = |x: f32, z: f32| ground.map_or(0.0, |g| g.surface_height(x, z));
    let h = asset.header();
    let lowest = h.bounds_min[1];
    // The footprint's radius on the ground: the bounds' farthest corner from the y axis.
    let reach = [h.bounds_min, h.bounds_max]
        .iter()
        .flat_map(|a| [h.bounds_min, h.bounds_max].map(move |b| Vec3::new(a[0], 0.0, b[2])))
        .map(Vec3::length)
        .fold(0.0f32, f32::max);
    let mut rng = Rng(0x6d65_7368_6c69_6768);
    for i in 0..instances {
        let (col, row) = (i % side, i / side);
        let jitter = Vec3::new(rng.unit() - 0.5, 0.0, rng.unit() - 0.5) * spacing * 0.3;
        let at = Vec3::new(col as f32, 0.0, row as f32) * spacing + jitter;
        let scale = 0.8 + 0.4 * rng.unit();
        let turn = Quat::from_rotation_y(rng.unit() * std::f32::consts::TAU);
        // The lowest point on the ground under the middle half of the footprint: no
        // copy floats on a slope, and one on a hillside sinks a little into it.
        let under = (0..8)
            .map(|k| {
                let a = k as f32 * std::f32::consts::FRAC_PI_4;
                let r = reach * scale * 0.5;
                ground_at(at.x + r * a.cos(), at.z + r * a.sin())
            })
            .fold(ground_at(at.x, at.z), f32::min);
        let transform = Mat4::from_scale_rotation_translation(
            Vec3::splat(scale),
            turn,
            Vec3::new(at.x, under - lowest * scale, at.z),
        );
        copies.place(&mut data, i as usize, transform)?;
    }
    if let Some(ground) = ground {
        let ground_asset = ground_asset(&ground).map_err(|e| {
            meshlight::gpu_scene::SceneDataError::InvalidAsset {
                name: "ground (procedural terrain)".into(),
                reason: e.to_string(),
            }
        })?;
        let ground_mesh = add_mesh(&mut data, &mut copies.sources, "ground", &ground_asset)?;
        let material = data.add_material(Material {
            base_color: GROUND_COLOR,
            ..Material::default()
        })?;
        data.add_instance(ground_mesh, Mat4::IDENTITY, material)?;
    }
    let extent = side as f32 * spacing;
    let eye = Vec3::new(FIELD_EYE.0, 0.0, FIELD_EYE.1) * radius;
    let target = Vec3::new(extent * 0.7, 0.0, extent);
    let camera = Camera::perspective(
        eye + Vec3::Y * (ground_at(eye.x, eye.z) + radius * 3.0),
        target + Vec3::Y * (ground_at(target.x, target.z) + radius * 0.4),
        55f32.to_radians(),
        radius * 0.05,
    );
    Ok(Placed {
        data,
        camera,
        sources: copies.sources,
    })
}

/// Distance between neighbouring copies of a [`field`], in mesh radii.
const FIELD_SPACING: f32 = 2.6;
/// Where a [`field`]'s camera stands (x, z), in mesh radii: behind the first copy.
const FIELD_EYE: (f32, f32) = (-1.5, -1.5);
/// Linear albedo of the ground: a dry grass green.
pub const GROUND_COLOR: [f32; 3] = [0.40, 0.52, 0.28];
/// Most grid cells per side of a field's ground: 2 · 512² = 524,288 triangles, a bake of
/// about half a second on two cores (cached after the first).
pub const MAX_GROUND_CELLS: u32 = 512;

/// The ground under a [`field`] of `instances` copies of a mesh of bounding radius
/// `radius`: a square reaching from just behind the camera's corner to three field
/// widths beyond it, so the far edge lies near the horizon; hills 0.4 field widths
/// apart (at least twelve mesh radii) and rising 0.08 field widths (at least 1.5 radii),
/// so that they hide copies behind them (about two in five of the default scene's, seen
/// from the camera), calm where the camera stands; cells of about half a mesh radius (up
/// to [`MAX_GROUND_CELLS`]).
pub fn field_ground(radius: f32, instances: u32) -> Terrain {
    let side = (instances as f32).sqrt().ceil().max(1.0);
    let extent = side * radius * FIELD_SPACING;
    let origin = -0.5 * extent - 4.0 * radius;
    let size = 3.5 * extent + 4.0 * radius;
    let cells = ((size / (0.55 * radius)).ceil() as u32).clamp(16, MAX_GROUND_CELLS);
    Terrain {
        origin: glam::Vec2::splat(origin),
        size,
        cells,
        amplitude: (0.08 * extent).max(1.5 * radius),
        wavelength: (0.4 * extent).max(12.0 * radius),
        octaves: 5,
        seed: 0x6772_6e64,
        // Checker squares (8 per UV unit) of about a mesh radius.
        uv_scale: 1.0 / (8.0 * radius),
        // Flat where the camera stands, so the near copies are seen over level ground.
        calm_centre: glam::Vec2::new(FIELD_EYE.0, FIELD_EYE.1) * radius,
        calm_radius: 8.0 * radius,
    }
}

/// The baked asset of `terrain`: from this process's memory, else from the asset cache,
/// else baked (its progress logged) and stored in the cache. The cache file is named
/// by a hash of the terrain's fields, the asset format and the builder revision.
pub fn ground_asset(terrain: &Terrain) -> Result<MeshletAsset, SceneError> {
    static BAKED: Mutex<Vec<(u64, MeshletAsset)>> = Mutex::new(Vec::new());
    let key = ground_key(terrain);
    // Held while baking, so tests placing the same field at once bake it once.
    let mut baked = BAKED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, asset)) = baked.iter().find(|(k, _)| *k == key) {
        return Ok(asset.clone());
    }
    let dir = cache::cache_dir();
    let path = dir.join(format!("terrain-{key:016x}.mlasset"));
    let cached = path.exists().then(|| MeshletAsset::load(&path));
    let asset = match cached {
        Some(Ok(asset)) => asset,
        _ => {
            let mesh = terrain.mesh()?;
            let built = build_asset(&mesh, &BuildOptions::default(), &mut |p| {
                cache::log_progress(&mesh.source, p)
            })?;
            store(&built.asset, &dir, &path);
            built.asset
        }
    };
    baked.push((key, asset.clone()));
    Ok(asset)
}

/// FNV-1a over the terrain's fields and what else makes an asset differ.
fn ground_key(t: &Terrain) -> u64 {
    let words = [
        t.origin.x.to_bits(),
        t.origin.y.to_bits(),
        t.size.to_bits(),
        t.cells,
        t.amplitude.to_bits(),
        t.wavelength.to_bits(),
        t.octaves,
        t.seed,
        t.uv_scale.to_bits(),
        format::VERSION,
        cache::BUILDER_REVISION,
    ];
    let text = format!("{words:?} {}", env!("CARGO_PKG_VERSION"));
    text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Writes through a temporary file and a rename; a failure only costs a bake next time.
fn store(asset: &MeshletAsset, dir: &Path, path: &Path) {
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    let stored = std::fs::create_dir_all(dir)
        .map_err(|e| e.to_string())
        .and_then(|()| asset.save(&tmp).map_err(|e| e.to_string()))
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
    if let Err(e) = stored {
        log::warn!("could not cache the baked ground in {}: {e}", dir.display());
    }
}

/// An `n × n × n` lattice of `asset` (the virtual-geometry benchmark's 15³ bunnies),
/// seen from outside one corner so the whole lattice is in view.
pub fn lattice(
    mut data: SceneData,
    asset: &MeshletAsset,
    n: u32,
) -> Result<Placed, meshlight::gpu_scene::SceneDataError> {
    let copies = Copies::add(&mut data, asset)?;
    let lattice = Lattice {
        n,
        radius: copies.radius,
    };
    for (i, transform) in lattice.transforms().enumerate() {
        copies.place(&mut data, i, transform)?;
    }
    Ok(Placed {
        data,
        camera: lattice.camera(),
        sources: copies.sources,
    })
}

/// Every `.mlasset` file under `dir` and its folders (what `meshlight bake DIR -o OUT`
/// writes), in path order, opened in parallel: whole with every check `inspect` runs,
/// or with `streamed` only their resident parts ([`open_asset`]). Each comes with its
/// path relative to `dir`, its name in messages.
pub fn load_library(dir: &Path, streamed: bool) -> Result<Vec<(String, MeshletAsset)>, SceneError> {
    use rayon::prelude::*;
    let mut files = Vec::new();
    let mut folders = vec![dir.to_path_buf()];
    while let Some(folder) = folders.pop() {
        let entries = std::fs::read_dir(&folder).map_err(|source| SceneError::Io {
            path: folder.clone(),
            source,
        })?;
        for entry in entries {
            let entry = entry.map_err(|source| SceneError::Io {
                path: folder.clone(),
                source,
            })?;
            let path = entry.path();
            // Links are not followed: a link to a parent would never end.
            let kind = entry.file_type().map_err(|source| SceneError::Io {
                path: path.clone(),
                source,
            })?;
            if kind.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == "mlasset") {
                files.push(path);
            }
        }
    }
    if files.is_empty() {
        return Err(SceneError::InvalidOption(format!(
            "{} holds no .mlasset files; bake a directory of meshes into it first \
             (`meshlight bake MESHES -o {}`)",
            dir.display(),
            dir.display()
        )));
    }
    files.sort();
    files
        .par_iter()
        .map(|path| {
            let name = path.strip_prefix(dir).unwrap_or(path).display().to_string();
            Ok((name, open_asset(path, 0, streamed)?))
        })
        .collect()
}

/// A directory of baked assets as one scene ([`load_library`]): each asset once, where
/// it was baked (a generated world's tiles are baked in world space), in the palette's
/// colours in turn, lit by the sun, seen from above one corner of their bounds.
pub fn library(
    mut data: SceneData,
    assets: &[(String, MeshletAsset)],
) -> Result<Placed, meshlight::gpu_scene::SceneDataError> {
    let materials = palette(&mut data)?;
    let mut sources = Vec::new();
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for (i, (name, asset)) in assets.iter().enumerate() {
        let mesh = add_mesh(&mut data, &mut sources, name, asset)?;
        data.add_instance(mesh, Mat4::IDENTITY, materials[i % materials.len()])?;
        lo = lo.min(Vec3::from(asset.header().bounds_min));
        hi = hi.max(Vec3::from(asset.header().bounds_max));
    }
    let (centre, radius) = (0.5 * (lo + hi), (0.5 * (hi - lo)).length().max(1e-6));
    let camera = Camera::perspective(
        centre + Vec3::new(-0.7, 0.45, -0.7).normalize() * radius * 1.2,
        centre,
        50f32.to_radians(),
        radius * 1e-4,
    );
    Ok(Placed {
        data,
        camera,
        sources,
    })
}

/// One instance at the origin, and a camera that frames it (for `--instances 1`).
pub fn single(
    data: SceneData,
    asset: &MeshletAsset,
) -> Result<Placed, meshlight::gpu_scene::SceneDataError> {
    single_painted(data, asset, Paint::Palette)
}

/// [`single`] painted as `paint` says.
pub fn single_painted(
    data: SceneData,
    asset: &MeshletAsset,
    paint: Paint,
) -> Result<Placed, meshlight::gpu_scene::SceneDataError> {
    let mut placed = field_painted(data, asset, 1, paint)?;
    let mesh = &placed.data.meshes[0];
    let s = mesh.bounding_sphere;
    let centre = placed.data.instances.first().map_or(Vec3::ZERO, |i| {
        Mat4::from_cols_array_2d(&i.world_from_local).transform_point3(Vec3::new(s[0], s[1], s[2]))
    });
    placed.camera = Camera::perspective(
        centre + Vec3::new(0.45, 0.55, 1.0).normalize() * s[3] * 2.6,
        centre,
        40f32.to_radians(),
        s[3] * 0.05,
    );
    Ok(placed)
}

fn mesh_radius(data: &SceneData, mesh: MeshId) -> f32 {
    data.meshes[mesh.0 as usize].bounding_sphere[3].max(1e-6)
}

/// Lights of the default scene: `count` coloured point lights hovering over instances of
/// a [`field`], spread evenly over it, each reaching its neighbours' instances.
pub fn field_lights(placed: &Placed, count: u32) -> Vec<ClusterableObject> {
    // The copies (mesh 0), not the ground.
    let instances: Vec<_> = placed
        .data
        .instances
        .iter()
        .filter(|i| i.mesh == 0)
        .collect();
    if instances.is_empty() || count == 0 {
        return Vec::new();
    }
    let radius = placed
        .data
        .meshes
        .first()
        .map_or(1.0, |m| m.bounding_sphere[3].max(1e-6));
    let mut rng = Rng(0x6c69_6768_7473_0001);
    (0..count)
        .map(|i| {
            let instance = &instances[(i as usize * instances.len()) / count as usize];
            let at = Mat4::from_cols_array_2d(&instance.world_from_local)
                .w_axis
                .truncate();
            let offset = Vec3::new(rng.unit() - 0.5, 0.0, rng.unit() - 0.5) * radius * 2.0;
            let p = at + offset + Vec3::Y * radius * (1.2 + rng.unit());
            let hue = rng.unit() * std::f32::consts::TAU;
            point_light(p, radius * 3.5, radius, hue)
        })
        .collect()
}

/// A point light at `p` reaching `reach`, as bright as an object of `radius` beneath it
/// wants, its colour at `hue` (radians) around the colour wheel: the lights the scenes
/// hang over their instances.
pub(crate) fn point_light(p: Vec3, reach: f32, radius: f32, hue: f32) -> ClusterableObject {
    let color = [0.0f32, 2.1, 4.2].map(|phase| 0.55 + 0.45 * (hue + phase).cos());
    ClusterableObject {
        position_range: [p.x, p.y, p.z, reach],
        direction_cos_angle: [0.0, -1.0, 0.0, 1.0],
        color_intensity: [color[0], color[1], color[2], radius * radius * 4.0],
        kind: ClusterableKind::PointLight as u32,
        ..ClusterableObject::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshlight::gpu_scene::data::Limits;
    use meshlight::scene::procedural_mesh;

    fn small_asset() -> MeshletAsset {
        build_asset(&procedural_mesh(12), &BuildOptions::default(), &mut |_| {})
            .unwrap()
            .asset
    }

    #[test]
    fn the_copies_stand_on_the_ground_which_is_the_last_instance() {
        let asset = small_asset();
        let placed = field(SceneData::new(Limits::default()), &asset, 25).unwrap();
        let data = &placed.data;
        assert_eq!(data.instances.len(), 26);
        assert_eq!(data.meshes.len(), 2);
        let ground = data.instances[25];
        assert_eq!(ground.mesh, 1);
        let radius = data.meshes[0].bounding_sphere[3];
        let terrain = field_ground(radius, 25);
        let h = asset.header();
        assert_eq!(
            data.source_triangles(),
            25 * h.lod0_triangles as u64 + terrain.triangle_count()
        );
        let mut sunk = 0;
        for instance in &data.instances[..25] {
            assert_eq!(instance.mesh, 0);
            let m = Mat4::from_cols_array_2d(&instance.world_from_local);
            let centre = m.w_axis.truncate();
            let scale = m.x_axis.truncate().length();
            let lowest = centre.y + h.bounds_min[1] * scale;
            let below = terrain.surface_height(centre.x, centre.z);
            // Never above the ground under its middle: no copy floats.
            assert!(lowest <= below + 1e-4, "{lowest} over {below}");
            // Never buried: the lowest point is within a slope's reach of the ground.
            assert!(below - lowest < radius, "{lowest} under {below}");
            sunk += (below - lowest > 1e-3) as u32;
        }
        // The hills are real: some copies stand on slopes.
        assert!(sunk > 0);
    }

    #[test]
    fn the_default_fields_hills_hide_copies_from_the_camera_and_the_near_ones_do_not() {
        // Without baking: the ground's heights along the line from the camera to each
        // copy's middle (a radius above the ground), as placed for 1,024 copies.
        let radius = 1.0;
        let terrain = field_ground(radius, DEFAULT_INSTANCES);
        assert_eq!(terrain.cells, MAX_GROUND_CELLS);
        let eye = Vec3::new(FIELD_EYE.0, 0.0, FIELD_EYE.1) * radius;
        let eye = eye + Vec3::Y * (terrain.surface_height(eye.x, eye.z) + 3.0 * radius);
        let hidden = |x: f32, z: f32| {
            let target = Vec3::new(x, terrain.surface_height(x, z) + radius, z);
            (1..64).any(|k| {
                let p = eye.lerp(target, k as f32 / 64.0);
                terrain.surface_height(p.x, p.z) > p.y
            })
        };
        let spacing = radius * FIELD_SPACING;
        let side = 32;
        let count = (0..side * side)
            .filter(|i| hidden((i % side) as f32 * spacing, (i / side) as f32 * spacing))
            .count();
        eprintln!("{count} of 1,024 copies are behind hills");
        assert!(
            (200..900).contains(&count),
            "{count} of 1,024 copies are behind hills"
        );
        assert!((0..4).all(|i| !hidden(i as f32 * spacing, 0.0)));
    }
}
