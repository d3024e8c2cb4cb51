// The depth pyramid: a min-depth mip chain of the 64-bit visibility target.
// `meshlight_shaders::cpu::occlusion::DepthPyramid` is the reference; lib.rs states the
// footprint rule this implements.
//
// Depths are handled as their u32 bits throughout. The rasterisers store clamped,
// non-negative depths (0 = empty = far, with reverse-Z), whose bits order like the floats,
// so a u32 min is the float min and every stored texel is exactly one source depth.
//
// A workgroup reduces one block of its input into the levels above it, down to 1 texel.
// In the first step the input is the visibility target, the block a 128 × 128 tile and
// the levels 0 to 6; in the top step it is the grid of tile results (one texel of level
// 6 per tile), the block the smallest of 32², 64² or 128² tiles covering the grid, and
// the levels 7 up to 11, 12 or 13.

// The uniform block, declared once for Rust and WGSL by `ShaderParams` in lib.rs.
#import depth_pyramid::params::Params

#ifdef VIS_TEXTURE
// The software rasteriser's `texture` target: an R64Uint storage texture.
@group(0) @binding(0) var visibility: texture_storage_2d<r64uint, read>;
#else
// size.x × size.y visibility values, row-major, in the pair form (low word, high word).
@group(0) @binding(0) var<storage, read> visibility: array<vec2<u32>>;
#endif
// Per tile, row-major over `tiles`: the depth bits of its level-6 texel. Atomic so the
// workgroup that reads them in the single pass sees what others wrote (see single_pass).
@group(0) @binding(1) var<storage, read_write> tile_results: array<atomic<u32>>;
@group(0) @binding(2) var<uniform> params: Params;
#ifdef SINGLE_PASS
// Workgroups of this dispatch that have finished their tile; the last one sets it back
// to 0 for the next dispatch.
@group(0) @binding(3) var<storage, read_write> arrivals: atomic<u32>;
#endif

// One write-only view per level, level `params.level_base + binding`. Bindings past the
// last level hold a view that is never written.
@group(1) @binding(0) var mip0: texture_storage_2d<r32float, write>;
@group(1) @binding(1) var mip1: texture_storage_2d<r32float, write>;
@group(1) @binding(2) var mip2: texture_storage_2d<r32float, write>;
@group(1) @binding(3) var mip3: texture_storage_2d<r32float, write>;
@group(1) @binding(4) var mip4: texture_storage_2d<r32float, write>;
@group(1) @binding(5) var mip5: texture_storage_2d<r32float, write>;
@group(1) @binding(6) var mip6: texture_storage_2d<r32float, write>;
#ifdef SINGLE_PASS
@group(1) @binding(7) var mip7: texture_storage_2d<r32float, write>;
@group(1) @binding(8) var mip8: texture_storage_2d<r32float, write>;
@group(1) @binding(9) var mip9: texture_storage_2d<r32float, write>;
@group(1) @binding(10) var mip10: texture_storage_2d<r32float, write>;
@group(1) @binding(11) var mip11: texture_storage_2d<r32float, write>;
@group(1) @binding(12) var mip12: texture_storage_2d<r32float, write>;
@group(1) @binding(13) var mip13: texture_storage_2d<r32float, write>;
#endif

// The identity of min: what lies outside the image or the tile grid.
const NONE: u32 = 0xffffffffu;
// Levels one workgroup produces from its 128 × 128 input block.
const BLOCK_LEVELS: u32 = 7u;

// Level `level`'s size: ceil(size / 2^(level + 1)).
fn level_size(level: u32) -> vec2<u32> {
    return ((params.size - 1u) >> vec2(level + 1u)) + 1u;
}

// Writes one texel of `level`, if the level exists and the texel lies inside it.
fn store_level(level: u32, texel: vec2<u32>, bits: u32) {
    if level >= params.levels || any(texel >= level_size(level)) {
        return;
    }
    let v = vec4(bitcast<f32>(bits), 0.0, 0.0, 0.0);
    switch level - params.level_base {
        case 0u: { textureStore(mip0, texel, v); }
        case 1u: { textureStore(mip1, texel, v); }
        case 2u: { textureStore(mip2, texel, v); }
        case 3u: { textureStore(mip3, texel, v); }
        case 4u: { textureStore(mip4, texel, v); }
        case 5u: { textureStore(mip5, texel, v); }
        case 6u: { textureStore(mip6, texel, v); }
#ifdef SINGLE_PASS
        case 7u: { textureStore(mip7, texel, v); }
        case 8u: { textureStore(mip8, texel, v); }
        case 9u: { textureStore(mip9, texel, v); }
        case 10u: { textureStore(mip10, texel, v); }
        case 11u: { textureStore(mip11, texel, v); }
        case 12u: { textureStore(mip12, texel, v); }
        case 13u: { textureStore(mip13, texel, v); }
#endif
        default: {}
    }
}

// The depth bits of a visibility pixel (its high word); NONE outside the image.
fn pixel_bits(p: vec2<u32>) -> u32 {
    if any(p >= params.size) {
        return NONE;
    }
#ifdef VIS_TEXTURE
    return u32(textureLoad(visibility, p).x >> 32u);
#else
    return visibility[p.y * params.size.x + p.x].y;
#endif
}

// A tile's result; NONE outside the tile grid.
fn tile_bits(p: vec2<u32>) -> u32 {
    if any(p >= params.tiles) {
        return NONE;
    }
    return atomicLoad(&tile_results[p.y * params.tiles.x + p.x]);
}

fn input_bits(from_tiles: bool, p: vec2<u32>) -> u32 {
    if from_tiles {
        return tile_bits(p);
    }
    return pixel_bits(p);
}

// The min of the 2 × 2 input texels under output texel `texel`.
fn quad_min(from_tiles: bool, texel: vec2<u32>) -> u32 {
    let p = texel * 2u;
    let top = min(input_bits(from_tiles, p), input_bits(from_tiles, p + vec2(1u, 0u)));
    let bottom = min(input_bits(from_tiles, p + vec2(0u, 1u)), input_bits(from_tiles, p + vec2(1u, 1u)));
    return min(top, bottom);
}

// 16 × 16 texels of level `first + patch_log`, then the levels above them, one per step.
var<workgroup> cells: array<u32, 256>;

// Reduces the (16 · 2^patch_log)² texels `block` of level `first` and the levels above
// them up to its one texel of level `first + patch_log + 4`, writing each; returns that
// texel (in thread 0).
//
// Each thread first reduces a 2^patch_log-square patch of level `first` in registers,
// visiting its texels in Morton order so that every fourth closes a texel of level
// `first + 1` and every sixteenth one of `first + 2`; the last four levels go through
// workgroup memory, from 16 × 16 cells of level `first + patch_log`. Texels partly
// outside the image take the min of their inside part (outside inputs are NONE); texels
// wholly outside are computed and not written.
//
// The first step takes patch_log 2 (a 128 × 128 tile, seven levels, 64 input pixels a
// thread). The top step takes the smallest patch that covers the tile grid: up to 4096
// pixels a side, each of its threads loads four tile results rather than sixty-four.
// Its one workgroup runs alone at the end of the pass, so its loads are the pass's tail.
fn reduce_block(from_tiles: bool, block: vec2<u32>, first: u32, patch_log: u32, local: u32) -> u32 {
    let thread = vec2(local % 16u, local / 16u);
    // The thread's first texel of level `first`.
    let corner = (block * 16u + thread) << vec2(patch_log);
    var patch_bits = NONE;
    var quad_bits = NONE;
    var square_bits = NONE;
    for (var i = 0u; i < 1u << (2u * patch_log); i++) {
        // Bits 0, 2 of i are the offset's x; bits 1, 3 its y.
        let offset = vec2((i & 1u) | ((i >> 1u) & 2u), ((i >> 1u) & 1u) | ((i >> 2u) & 2u));
        let texel = corner + offset;
        let bits = quad_min(from_tiles, texel);
        store_level(first, texel, bits);
        patch_bits = min(patch_bits, bits);
        quad_bits = min(quad_bits, bits);
        if (i & 3u) == 3u {
            store_level(first + 1u, texel >> vec2(1u), quad_bits);
            square_bits = min(square_bits, quad_bits);
            quad_bits = NONE;
        }
        if (i & 15u) == 15u {
            store_level(first + 2u, texel >> vec2(2u), square_bits);
            square_bits = NONE;
        }
    }
    cells[local] = patch_bits;
    var bits = patch_bits;
    // Levels first + patch_log + 1 ..= first + patch_log + 4: 8 × 8 texels of the block
    // down to 1, each from the 2 × 2 cells (row-major, twice the side) below it.
    for (var k = 1u; k <= 4u; k++) {
        let side = 16u >> k;
        let below = side * 2u;
        let texel = vec2(local % side, local / side);
        workgroupBarrier();
        if local < side * side {
            let i = texel.y * 2u * below + texel.x * 2u;
            bits = min(min(cells[i], cells[i + 1u]), min(cells[i + below], cells[i + below + 1u]));
            store_level(first + patch_log + k, block * side + texel, bits);
        }
        workgroupBarrier();
        if local < side * side {
            cells[local] = bits;
        }
    }
    return bits;
}

// The first step's patch: 4 × 4 pixel quads a thread, 128 × 128 pixels a tile.
const TILE_PATCH_LOG: u32 = 2u;

// The top step's patch: the smallest whose block (16 · 2^patch_log texels of level 7,
// twice that many tiles a side) covers the tile grid.
fn top_patch_log() -> u32 {
    let tiles = max(params.tiles.x, params.tiles.y);
    if tiles <= 32u {
        return 0u;
    }
    if tiles <= 64u {
        return 1u;
    }
    return 2u;
}

// The first step: workgroup (x, y) reduces tile (x, y) of the visibility target into
// levels 0 to 6 and, where levels above 6 exist, publishes its level-6 texel.
fn reduce_tile(tile: vec2<u32>, local: u32) {
    let bits = reduce_block(false, tile, 0u, TILE_PATCH_LOG, local);
    if local == 0u && params.levels > BLOCK_LEVELS {
        atomicStore(&tile_results[tile.y * params.tiles.x + tile.x], bits);
    }
}

// two_pass, first dispatch: one workgroup per tile.
@compute @workgroup_size(256)
fn tiles(
    @builtin(workgroup_id) tile: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    reduce_tile(tile.xy, local);
}

// two_pass, second dispatch (one workgroup, only when levels > 7): levels 7 and up from
// the tile results, which the first dispatch wrote.
@compute @workgroup_size(256)
fn top(@builtin(local_invocation_index) local: u32) {
    reduce_block(true, vec2(0u), BLOCK_LEVELS, top_patch_log(), local);
}

#ifdef SINGLE_PASS
// 1 in the workgroup that counted itself last.
var<workgroup> is_last: u32;

// single_pass: one workgroup per tile, and the last one to finish its tile goes on to
// reduce all tile results into levels 7 and up. Nobody waits for anybody, so this needs
// no forward-progress guarantee.
//
// The hand-off. Each workgroup stores its result with an atomic store, then every thread
// passes storageBarrier() (naga: OpControlBarrier with device memory scope and
// acquire-release semantics on storage memory) before thread 0 counts the workgroup in
// with atomicAdd: the result is released before the count. The workgroup whose atomicAdd
// returns tiles - 1 has seen every other workgroup's count, each made after its result
// was released; it passes storageBarrier() again (acquire) before any thread loads a
// result, and loads them with atomicLoad, which reads device-coherent memory rather
// than a cache another workgroup's write could be missing from. Texture texels written
// by other workgroups are never read.
@compute @workgroup_size(256)
fn single_pass(
    @builtin(workgroup_id) tile: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    reduce_tile(tile.xy, local);
    if params.levels <= BLOCK_LEVELS {
        // One tile covers the image: the pyramid is complete.
        return;
    }
    storageBarrier();
    if local == 0u {
        let before = atomicAdd(&arrivals, 1u);
        is_last = u32(before + 1u == params.tiles.x * params.tiles.y);
    }
    if workgroupUniformLoad(&is_last) == 0u {
        return;
    }
    storageBarrier();
    if local == 0u {
        atomicStore(&arrivals, 0u);
    }
    reduce_block(true, vec2(0u), BLOCK_LEVELS, top_patch_log(), local);
}
#endif
