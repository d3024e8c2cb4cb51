#define_import_path meshlight::occlusion

// Occlusion of a bounding sphere by a depth pyramid, conservative: a sphere is reported
// hidden only when every pixel it could cover already holds a nearer surface. The Rust
// mirror is `meshlight_shaders::cpu::occlusion`, operation for operation; the one
// function it lacks, `instance_sphere_rect`, only chains `meshlight::instance`'s transform
// and scale into `occlusion_rect`, and the passes' CPU references (cull_lod's
// `cpu::occlusion_test`, fill_clusters' `hierarchy_cpu::node_occlusion`) chain their
// mirrors of those the same way.
//
// The pyramid is an R32Float texture over a W × H reverse-Z depth image (near = 1, far
// or empty = 0). Each texel holds the minimum, i.e. the farthest, depth of its
// footprint: level L is ceil(W / 2^(L+1)) × ceil(H / 2^(L+1)) and its texel (x, y)
// covers the pixels [x·2^(L+1), (x+1)·2^(L+1)) × [y·2^(L+1), (y+1)·2^(L+1)), clipped to
// the image. So one texel at level L answers "how far is the farthest surface under
// these 2^(L+1) × 2^(L+1) pixels".

#import meshlight::math::{F32_MAX, max_component}
#import meshlight::instance::{Instance, instance_max_scale, instance_transform_point}
#import meshlight::view::View

// Pixels added on every side of a sphere's screen rectangle: covers the rasterisers'
// sub-pixel snapping and the rounding of the projection.
const OCCLUSION_MARGIN_PX: f32 = 1.0;
// Relative slack on the radius, against world-space rounding: the rasterisers transform
// each vertex on its own, and their positions may differ from this centre ± radius by
// a few ulps of the coordinates' magnitude.
const OCCLUSION_RADIUS_SLACK: f32 = 1e-5;
// A sphere counts as hidden only when its nearest depth times this is still farther
// than the pyramid's farthest: room for the rasterisers' depth interpolation.
const OCCLUSION_DEPTH_SLACK: f32 = 1.00390625; // 1 + 2^-8

// A sphere's footprint on the screen, or the reason it has none that can be tested.
struct OcclusionRect {
    // False when the sphere reaches the near plane (or behind the eye) or its rectangle
    // is not wholly on the screen: such a sphere is never culled by occlusion.
    testable: bool,
    // Inclusive pixel range (x0, y0, x1, y1), margin included.
    pixels: vec4<u32>,
    // The nearest reverse-Z depth of the sphere (largest depth of its bounding cube).
    depth: f32,
}

// The screen rectangle and nearest depth of a world-space sphere seen through
// `view_projection` (reverse-Z) on a `viewport` of pixels (screen y down). The eight
// corners of the sphere's world-space bounding cube are projected: with all of them in
// front of the near plane the cube projects inside their bounding box, and its nearest
// depth is at a corner.
fn occlusion_rect(view_projection: mat4x4<f32>, viewport: vec2<f32>, center: vec3<f32>, radius: f32) -> OcclusionRect {
    var rect: OcclusionRect;
    rect.testable = false;
    rect.pixels = vec4(0u);
    rect.depth = 0.0;
    let r = radius + OCCLUSION_RADIUS_SLACK * (max_component(abs(center)) + radius);
    let c = view_projection * vec4(center, 1.0);
    let ex = view_projection[0] * r;
    let ey = view_projection[1] * r;
    let ez = view_projection[2] * r;
    var lo = vec2(F32_MAX);
    var hi = vec2(-F32_MAX);
    var depth = 0.0;
    for (var k = 0u; k < 8u; k += 1u) {
        let clip = c + select(-ex, ex, (k & 1u) != 0u) + select(-ey, ey, (k & 2u) != 0u)
            + select(-ez, ez, (k & 4u) != 0u);
        // Behind the eye, nearer than the near plane, or NaN: not testable.
        if !(clip.w > 0.0 && clip.z < clip.w) {
            return rect;
        }
        let ndc = clip.xyz / clip.w;
        let screen = vec2((ndc.x * 0.5 + 0.5) * viewport.x, (0.5 - ndc.y * 0.5) * viewport.y);
        lo = min(lo, screen);
        hi = max(hi, screen);
        depth = max(depth, ndc.z);
    }
    lo = lo - vec2(OCCLUSION_MARGIN_PX);
    hi = hi + vec2(OCCLUSION_MARGIN_PX);
    // Partly off the screen: the pyramid knows nothing of what lies outside it.
    if !(lo.x >= 0.0 && lo.y >= 0.0 && hi.x < viewport.x && hi.y < viewport.y) {
        return rect;
    }
    rect.testable = true;
    rect.pixels = vec4(u32(lo.x), u32(lo.y), u32(hi.x), u32(hi.y));
    rect.depth = depth;
    return rect;
}

// The screen rectangle of a mesh-space `sphere` of `instance`, seen as the importing
// pass's occlusion test sees it. A first pass tests against last frame's pyramid, so it
// projects through last frame's view-projection and the instance's previous transform;
// a pass composed with SECOND_PASS defined tests against this frame's, through the
// current ones. naga_oil composes this module with the importing shader's defs, so the
// choice follows that shader's SECOND_PASS. One place for it keeps the per-cluster test
// (cull_lod) and the per-node test (fill_clusters' hierarchy) projecting alike.
fn instance_sphere_rect(instance: Instance, view: View, sphere: vec4<f32>) -> OcclusionRect {
    var seen = instance;
#ifdef SECOND_PASS
    let view_projection = view.view_projection;
#else
    seen.world_from_local = instance.previous_world_from_local;
    let view_projection = view.previous_view_projection;
#endif
    let center = instance_transform_point(seen, sphere.xyz);
    let radius = sphere.w * instance_max_scale(seen);
    return occlusion_rect(view_projection, view.viewport_size, center, radius);
}

// The finest pyramid level at which the rectangle covers at most 2 × 2 texels: a texel
// of level L spans 2^(L+1) pixels, more than the rectangle's extent when
// L = floor(log2(extent)).
fn occlusion_level(pixels: vec4<u32>) -> u32 {
    let extent = max(pixels.z - pixels.x, pixels.w - pixels.y);
    return firstLeadingBit(max(extent, 1u));
}

// The farthest depth the pyramid holds under the rectangle: the minimum of the (at most
// 2 × 2) texels of its level that cover it. 0 (nothing is nearer than "empty") when the
// pyramid has too few levels for the rectangle to fit in 2 × 2 texels.
fn pyramid_farthest(pyramid: texture_2d<f32>, pixels: vec4<u32>) -> f32 {
    let level = occlusion_level(pixels);
    if level >= textureNumLevels(pyramid) {
        return 0.0;
    }
    // The rectangle is on the screen, so its texels lie inside the level. (No clamp by
    // `textureDimensions(pyramid, level)`: with a level not known at compile time,
    // lavapipe answered with another level's size.)
    let lo = pixels.xy >> vec2(level + 1u);
    let hi = pixels.zw >> vec2(level + 1u);
    var farthest = F32_MAX;
    for (var y = lo.y; y <= hi.y; y += 1u) {
        for (var x = lo.x; x <= hi.x; x += 1u) {
            farthest = min(farthest, textureLoad(pyramid, vec2(x, y), i32(level)).x);
        }
    }
    return farthest;
}

// True when the pyramid proves the sphere hidden: the rectangle is testable and every
// pixel under it holds a surface nearer than the sphere's nearest point.
fn sphere_occluded(pyramid: texture_2d<f32>, rect: OcclusionRect) -> bool {
    if !rect.testable {
        return false;
    }
    return rect.depth * OCCLUSION_DEPTH_SLACK < pyramid_farthest(pyramid, rect.pixels);
}
