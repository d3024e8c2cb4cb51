//! The command line's arguments that more than one command takes, and the parsers that
//! turn names into the library's values (the lists in `--help` come from the library, so
//! they cannot fall behind it).

use meshlight::resolve::DebugView;
use meshlight::scene::compress::PositionBits;
use meshlight::scene::load::DEFAULT_TRIANGLE_BUDGET;
use meshlight::scene::mesh::MAX_TRIANGLES;
use meshlight::scene::{DEFAULT_SEGMENTS, Grouping, World};
use meshlight_virtual_geometry::setup::ShadowRequest;
use meshlight_virtual_geometry::{SceneOptions, scenes};
use std::path::PathBuf;

/// The scene `render` and `view` draw.
#[derive(clap::Args)]
pub struct SceneArgs {
    /// Mesh file (.obj, .gltf, .glb, .stl, or a baked .mlasset), or `procedural`. A glTF
    /// file is drawn as its scene: each mesh baked once, each node that places it an
    /// instance, framed by a camera that sees it all (--camera-index picks one of the
    /// file's); --instances and the field apply to the other formats, or to a glTF file
    /// with --merge-gltf.
    #[arg(long, default_value = "procedural")]
    pub mesh: PathBuf,
    /// Bake a glTF file's scene into one mesh and place copies of it on the field, as for
    /// the other formats.
    #[arg(long)]
    pub merge_gltf: bool,
    /// Look through the glTF scene's camera N (0 is the first camera node in the
    /// scene's order) instead of one that frames the scene.
    #[arg(long, value_name = "N")]
    pub camera_index: Option<usize>,
    /// Tube segments of the procedural mesh (16 × segments² triangles; 256 ≈ 1M).
    #[arg(long, default_value_t = DEFAULT_SEGMENTS)]
    pub segments: u32,
    /// Copies of the mesh on the ground (1: one copy, framed by the camera).
    #[arg(long, default_value_t = scenes::DEFAULT_INSTANCES)]
    pub instances: u32,
    /// Coloured point lights over the field, clustered on the GPU and shaded per pixel
    /// (0: none; a single instance has none). `--view light-count` shows them per froxel.
    /// Default: 256, or 0 with a --pipeline file that clusters no lights (has no
    /// `z_slice` pass).
    #[arg(long)]
    pub lights: Option<u32>,
    /// A pipeline file to render with instead of the graph built in code, e.g.
    /// pipelines/virtual_geometry.toml or your own composition of the same resources.
    /// The file's own settings stand unless a flag is given (--view overrides its
    /// resolve's `view`, --clusters and --slots its list sizes). The shipped file
    /// clusters the lights as the frame built in code does and renders the same image.
    /// `view` watches it: saving it rebuilds the frame, and an error in it is shown
    /// while the last good graph keeps rendering.
    #[arg(long)]
    pub pipeline: Option<PathBuf>,
    /// What the image shows (default: shaded, or with --pipeline the view the file's
    /// resolve names; `view` changes it live in the overlay). `occlusion`: green where
    /// the first culling pass drew the cluster, blue where the second did, redder the
    /// more of the instance occlusion culled (a still renders one frame before, so the
    /// frame has a history to cull against). `light-count` needs lights.
    #[arg(long, value_parser = view_parser())]
    pub view: Option<DebugView>,
    /// Image width in pixels (with `view`, the window's first width).
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    /// Image height in pixels (with `view`, the window's first height).
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Stream the meshes' geometry through a GPU pool of this many MiB: only the roots
    /// and the culling data stay resident, and the pages the view needs are read into
    /// the pool (least recently used ones evicted; a pool too small for the view draws
    /// it coarser, never with holes). Default: every page resident, unless baked assets
    /// (a .mlasset or a directory of them) hold more geometry than the adapter binds:
    /// those stream through the pool `meshlight info` names. A still renders once
    /// streaming has settled for the view.
    #[arg(long, value_name = "MIB", value_parser = clap::value_parser!(u64).range(1..=1 << 20))]
    pub pool_mb: Option<u64>,
    /// Direction towards the sun, `x,y,z` in world space (any length); default: the
    /// pipeline's (the shipped frame's sun is up and to the left, `-0.5,0.8,0.35`).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_direction, allow_hyphen_values = true)]
    pub sun: Option<[f32; 3]>,
    #[command(flatten)]
    pub shadows: ShadowArgs,
}

/// The sun's shadow.
#[derive(clap::Args)]
pub struct ShadowArgs {
    /// Shadow cascades, 0 to 4 (0: no shadow). Default: 4 where the pipeline has the
    /// shadow stage (the shipped frame does), else 0. `--view shadow` colours them.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=4))]
    pub shadow_cascades: Option<u32>,
    /// Texels along each side of a cascade's map: 16 to 16384, a multiple of 8 (default:
    /// the viewport's longer side, from 256 to 2048).
    #[arg(long, value_name = "TEXELS")]
    pub shadow_resolution: Option<u32>,
    /// How far from the camera shadows reach, in world units (default: where the median
    /// instance looks 8 pixels across, or the scene's far side if nearer).
    #[arg(long, value_name = "DISTANCE")]
    pub shadow_distance: Option<f32>,
    /// How the view is split between cascades: 0 uniformly, 1 logarithmically (each
    /// cascade covers the same ratio of distances), between: a blend.
    #[arg(long, value_name = "LAMBDA", default_value_t = 0.8)]
    pub shadow_split: f32,
    /// How much larger than its slice of the view a cascade's map reaches, as a fraction
    /// of the slice's radius, 0 to 1: the map is kept while the camera moves within
    /// twice that, at the cost of texels that much larger; 0 fits each map to its slice
    /// and draws every cascade again whenever the camera moves.
    #[arg(long, value_name = "FRACTION", default_value_t = meshlight::gpu_scene::cascades::DEFAULT_HOLD)]
    pub shadow_hold: f32,
    /// How far a receiver moves towards the sun before it is compared, in texels of its
    /// cascade (against acne on surfaces facing the sun).
    #[arg(long, value_name = "TEXELS", default_value_t = 1.0)]
    pub shadow_depth_bias: f32,
    /// How far a receiver moves along its normal, in texels of its cascade (against acne
    /// where the sun grazes).
    #[arg(long, value_name = "TEXELS", default_value_t = 1.0)]
    pub shadow_normal_bias: f32,
    /// The shadow views' LOD threshold is the camera's times 2^bias (1: twice the error,
    /// fewer triangles drawn into the maps).
    #[arg(
        long,
        value_name = "BIAS",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub shadow_lod_bias: f32,
}

/// `x,y,z`: three finite numbers, not all zero.
fn parse_direction(text: &str) -> Result<[f32; 3], String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let numbers: Option<Vec<f32>> = parts.iter().map(|p| p.parse::<f32>().ok()).collect();
    match numbers.as_deref() {
        Some(&[x, y, z]) if [x, y, z].iter().all(|c| c.is_finite()) && [x, y, z] != [0.0; 3] => {
            Ok([x, y, z])
        }
        _ => Err(format!(
            "`{text}` is not a direction: give three finite numbers, not all zero, as x,y,z (e.g. -0.5,0.8,0.35)"
        )),
    }
}

impl SceneArgs {
    /// The library's options for this scene.
    pub fn options(&self) -> SceneOptions {
        SceneOptions {
            mesh: self.mesh.clone(),
            segments: self.segments,
            instances: self.instances,
            lights: self.lights,
            pipeline: self.pipeline.clone(),
            view: self.view,
            width: self.width,
            height: self.height,
            merge_gltf: self.merge_gltf,
            camera: self.camera_index,
            pool_mb: self.pool_mb,
            sun: self.sun.map(meshlight::glam::Vec3::from_array),
            shadows: self.shadows.request(),
        }
    }
}

impl ShadowArgs {
    /// The library's shadow request.
    pub fn request(&self) -> ShadowRequest {
        ShadowRequest {
            cascades: self.shadow_cascades,
            resolution: self.shadow_resolution,
            distance: self.shadow_distance,
            split_lambda: self.shadow_split,
            hold: self.shadow_hold,
            depth_bias: self.shadow_depth_bias,
            normal_bias: self.shadow_normal_bias,
            lod_bias: self.shadow_lod_bias,
        }
    }
}

/// The views' names, listed by `--help` and in the error for one that does not exist,
/// taken from the views the resolve pass has.
fn view_parser() -> impl clap::builder::TypedValueParser<Value = DebugView> {
    use clap::builder::TypedValueParser as _;
    clap::builder::PossibleValuesParser::new(DebugView::ALL.map(DebugView::name))
        .try_map(|name| DebugView::parse(&name))
}

/// The generated world `generate` writes (see `meshlight::scene::World`).
#[derive(clap::Args, Debug, Clone)]
pub struct GenerateArgs {
    /// Directory to write the meshes under (`ground/…glb`, `knots/…glb`).
    pub output: PathBuf,
    /// Tiles per side: tiles² grounds and as many knots.
    #[arg(long, default_value_t = World::default().tiles, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub tiles: u32,
    /// Side of a tile, in world units.
    #[arg(long, default_value_t = World::default().tile_size)]
    pub tile_size: f32,
    /// Grid cells per tile side (2 · cells² triangles a ground).
    #[arg(long, default_value_t = World::default().cells, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub cells: u32,
    /// Tube segments of each knot (16 · segments² triangles); 0: no knots.
    #[arg(long, default_value_t = World::default().knot_segments, value_parser = clap::value_parser!(u32).range(0..=1024))]
    pub knot_segments: u32,
    /// Seed of the hills and the knots' shapes.
    #[arg(long, default_value_t = World::default().seed)]
    pub seed: u32,
}

impl GenerateArgs {
    /// The world these arguments describe.
    pub fn world(&self) -> World {
        World {
            tiles: self.tiles,
            tile_size: self.tile_size,
            cells: self.cells,
            knot_segments: self.knot_segments,
            seed: self.seed,
        }
    }
}

/// Build a meshlet LOD asset from a mesh file.
#[derive(clap::Args, Debug, Clone)]
pub struct BakeArgs {
    /// Mesh to bake: .obj, .gltf, .glb or .stl; `procedural` for the built-in torus knot.
    /// A directory bakes every mesh file under it.
    pub input: PathBuf,
    /// Asset file to write (conventionally *.mlasset), or the directory to mirror a
    /// directory of meshes under.
    #[arg(short, long)]
    pub output: PathBuf,
    /// How meshlets are grouped for simplification.
    #[arg(long, default_value = "partition", value_parser = grouping_parser())]
    pub grouping: Grouping,
    /// Bits per axis of the mesh-wide position grid: 4 to 24, or `auto` for the fewest
    /// whose error is at most 1/8 of the LOD-0 error.
    #[arg(long, default_value_t = PositionBits::Auto)]
    pub position_bits: PositionBits,
    /// Tube segments of the procedural mesh (16 × segments² triangles).
    #[arg(long, default_value_t = DEFAULT_SEGMENTS,
          value_parser = clap::value_parser!(u32).range(baked_segments()))]
    pub segments: u32,
    /// Most triangles a glTF scene's node tree may expand to (instances × their
    /// meshes' triangles), checked before anything is expanded.
    #[arg(long, default_value_t = DEFAULT_TRIANGLE_BUDGET,
          value_parser = clap::value_parser!(u64).range(1..=MAX_TRIANGLES))]
    pub max_triangles: u64,
    /// Meshes baked at once, and threads in all (default: every core). The outputs are
    /// the same bytes whatever the number.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub jobs: Option<u32>,
}

impl BakeArgs {
    /// The library's options for one mesh.
    pub fn options(&self) -> meshlight::scene::bake::BakeOptions {
        meshlight::scene::bake::BakeOptions {
            input: self.input.clone(),
            output: self.output.clone(),
            grouping: self.grouping,
            position_bits: self.position_bits,
            segments: self.segments,
            max_triangles: self.max_triangles,
        }
    }
}

/// The segments `bake` takes, the bound `render` gives a streamed mesh too.
fn baked_segments() -> std::ops::RangeInclusive<i64> {
    let range = meshlight_cli::render_bounds::BAKED_SEGMENTS;
    *range.start() as i64..=*range.end() as i64
}

fn grouping_parser() -> impl clap::builder::TypedValueParser<Value = Grouping> {
    use clap::builder::TypedValueParser as _;
    clap::builder::PossibleValuesParser::new(Grouping::ALL.map(Grouping::name))
        .try_map(|name| Grouping::parse(&name).ok_or("unknown grouping"))
}

/// Run benchmark scenarios.
#[derive(clap::Args, Debug, Clone)]
pub struct BenchArgs {
    /// Scenarios to run (default: all). Known: graph-compile, graph-execute, graph-floor
    /// (1, 16 and 256 dependent one-thread passes through the graph against the same
    /// dispatches in one raw wgpu compute pass), pool-reuse,
    /// render (the default scene at 1920x1080 and 3840x2160), textured (a textured mesh
    /// on the default field, then with MASK materials), virtual-geometry (15³ meshes at
    /// 2240x1260, the first --mesh or the bunny), vg-scale (1 to 32,768 copies of that
    /// mesh at 2240x1260: frame time and work tested), vg-million (1,048,576 copies at
    /// 2560x1440), vg-stream (the default scene and 15³ bunnies resident, then streamed
    /// with every page in the pool: what streaming costs a settled frame), vg-shadows
    /// (the sun's four cascades, drawn every frame and kept), lod-quality (per LOD
    /// threshold: triangles per pixel, frame, and SSIM/PSNR against LOD 0),
    /// rasterisers (the same scene: each implementation of sw_raster and hw_raster, and
    /// the software/hardware split sweep), builder, scan-fan, light-clustering (1,000 to
    /// 1,000,000 point lights at 1920x1080, both implementations, against the CPU
    /// reference).
    #[arg(long = "scenario", value_delimiter = ',')]
    pub scenarios: Vec<String>,
    /// Write the rows as JSON here too.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Fewer repeats and smaller sizes, for a quick look.
    #[arg(long)]
    pub quick: bool,
    /// Mesh files the `builder` scenario measures besides the procedural mesh
    /// (repeatable), e.g. `--mesh assets/meshes/stanford-bunny.obj`; the first is also
    /// the mesh of the `virtual-geometry` scenario.
    #[arg(long = "mesh")]
    pub meshes: Vec<PathBuf>,
    /// Write the rows as one page of charts here too (log-log lines for size sweeps,
    /// stacked bars for per-pass profiles, bars for the rest).
    #[arg(long)]
    pub html: Option<PathBuf>,
    /// Read the rows from these JSON files (written by `--json`) instead of measuring:
    /// with --html, charts of an earlier run, e.g. the GPU runs under docs/.
    #[arg(long = "from-json")]
    pub from_json: Vec<PathBuf>,
}

impl BenchArgs {
    /// The bench's options.
    pub fn options(self) -> meshlight_bench::BenchOptions {
        meshlight_bench::BenchOptions {
            scenarios: self.scenarios,
            json: self.json,
            quick: self.quick,
            meshes: self.meshes,
            html: self.html,
            from_json: self.from_json,
        }
    }
}
