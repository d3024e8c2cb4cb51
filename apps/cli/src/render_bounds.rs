//! Bounds on the numbers `meshlight render` takes, checked before a mesh is baked or an
//! adapter is requested. Each bound is what the renderer holds on any device with wgpu's
//! default limits (the limits the scene data is sized for, which every device meets),
//! taken from the sizes the renderer gives its buffers: a number inside a bound gets
//! past setup, and one outside it is refused at once, naming the limit, rather than
//! after a bake (`--segments 1024` took 41 s and 2.3 GB to be refused), after asking
//! for 275 GB (`--lights 4294967295`), or as a wgpu message naming no flag.
//!
//! `meshlight render --help` and `meshlight info` print [`bounds`], the list
//! [`RenderNumbers::check`] checks against.

use meshlight::gpu_scene::data::Limits as SceneLimits;
use meshlight::gpu_scene::gpu::elements::{CLUSTER, INSTANCE};
use meshlight::graph::Element;
use meshlight::z_slice::{CLUSTERABLE_OBJECT, SLICE_INSTANCE};
use meshlight_virtual_geometry::frame_graph::MAX_SLOTS;
use meshlight_virtual_geometry::setup::clustering_for;
use std::ops::RangeInclusive;

/// Tube segments of the procedural mesh that `meshlight bake` takes: at least 3 for a
/// closed tube, at most 1024 (16.7 M triangles). A render whose geometry streams
/// (`--pool-mb`) keeps only the roots and the culling data resident, and takes them all.
pub const BAKED_SEGMENTS: RangeInclusive<u64> = 3..=1024;

/// The most segments of a procedural mesh drawn resident. Its payload (the meshlets'
/// vertices and triangles) and the field's ground share the scene's `payload` binding,
/// [`SceneLimits::max_payload_words`]: 33,554,428 words with wgpu's default 128 MiB.
/// How many words a mesh bakes to is known only once baked, so the bound was measured
/// with the builder's default options: at 745 segments the mesh takes 31,233,554 words,
/// leaving 2,320,874 for the ground, which at its largest (512 × 512 cells, from 901
/// copies on) took 2,293,292 to 2,301,491 words over 33 copy counts from 901 to
/// 1,198,371; at 746 the mesh alone takes 31,346,356 words and no such ground fits
/// beside it (at 1024, 57,218,601).
/// `the_segment_bound_is_where_the_mesh_and_the_ground_stop_fitting`
/// (apps/cli/tests/render_bounds.rs) bakes both sides of the edge again.
pub const MAX_RESIDENT_SEGMENTS: u64 = 745;

/// The segments `render` takes: [`BAKED_SEGMENTS`] when the geometry streams, else up to
/// [`MAX_RESIDENT_SEGMENTS`].
pub fn segments(streamed: bool) -> RangeInclusive<u64> {
    match streamed {
        true => BAKED_SEGMENTS,
        false => *BAKED_SEGMENTS.start()..=MAX_RESIDENT_SEGMENTS,
    }
}

/// wgpu's default storage-binding size, in bytes: every buffer the renderer sizes from
/// a flag is bound whole, so this is the most any of them holds (the default
/// `max_buffer_size` is larger).
fn binding_bytes() -> u64 {
    let limits = wgpu::Limits::default();
    limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size)
}

/// The largest count of `element_size`-byte elements one binding holds.
fn per_binding(element_size: u32) -> u64 {
    binding_bytes() / u64::from(element_size)
}

/// The clustering's lists for `lights` lights, sized as the frame's setup sizes them
/// ([`clustering_for`]): each list's name and its bytes.
fn light_lists(lights: u64) -> [(&'static str, u64); 3] {
    let s = clustering_for([1, 1], lights);
    [
        (
            "object list",
            s.objects.saturating_mul(u64::from(CLUSTERABLE_OBJECT.size)),
        ),
        (
            "(object, slice) list",
            s.slice_instances
                .saturating_mul(u64::from(SLICE_INSTANCE.size)),
        ),
        (
            "froxel entry list (`cluster_objects`)",
            s.entries.saturating_mul(u64::from(Element::U32.size)),
        ),
    ]
}

/// The most lights the frame's clustering holds: its object list, its (object, slice)
/// list and its froxel entries are sized from the light count, and each is bound whole.
pub fn max_lights() -> u64 {
    let fits = |n: u64| light_lists(n).iter().all(|&(_, b)| b <= binding_bytes());
    // The lists grow with the count, so the largest count that fits is found by
    // bisection.
    let (mut lo, mut hi) = (0u64, u64::from(u32::MAX));
    while lo < hi {
        let mid = lo + (hi - lo).div_ceil(2);
        if fits(mid) { lo = mid } else { hi = mid - 1 }
    }
    lo
}

/// The list that stops fitting one light past [`max_lights`]: the one that binds.
fn binding_light_list() -> (&'static str, u64) {
    light_lists(max_lights() + 1)
        .into_iter()
        .find(|&(_, bytes)| bytes > binding_bytes())
        .unwrap_or(("froxel entry list (`cluster_objects`)", 0))
}

/// The most copies of the mesh: the instances the scene holds with wgpu's default
/// binding ([`SceneLimits::max_instances`], two bindings of instance records) less the
/// field's ground, which is an instance too.
pub fn max_instances() -> u64 {
    u64::from(SceneLimits::default().max_instances) - 1
}

/// The largest side of the image: wgpu's default 2-D texture limit, which every device
/// meets (the renderer checks the adapter's own limit again).
pub fn max_side() -> u64 {
    u64::from(wgpu::Limits::default().max_texture_dimension_2d)
}

/// The most pixels of the image: the visibility buffer holds a u64 a pixel in one
/// binding (a device with 64-bit texture atomics writes a texture instead, which holds
/// more; the bound is the one every device meets). The colour target, the depth pyramid
/// and the readback of the image hold less per pixel, or are textures.
pub fn max_pixels() -> u64 {
    per_binding(Element::U64.size)
}

/// The largest candidate-cluster list (and raster-slot list, which visibility ids also
/// bound): one binding of cluster records.
pub fn max_clusters() -> u64 {
    per_binding(CLUSTER.size)
}

/// The most raster slots: one binding of cluster records, and no more than a
/// visibility id's slot bits name.
pub fn max_slots() -> u64 {
    max_clusters().min(MAX_SLOTS)
}

/// What one bound holds: the flag (or flags, for a product), its range, which limit
/// binds it, and what to change when a number is past it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Bound {
    /// The flags whose number (or product) is bounded, without their dashes.
    pub flags: &'static [&'static str],
    pub range: RangeInclusive<u64>,
    /// The limit that binds, with its numbers.
    pub binds: String,
    /// What to change.
    pub fix: &'static str,
}

impl Bound {
    /// The flags as the command line spells them: `--lights`, `--width × --height`.
    pub fn name(&self) -> String {
        self.flags
            .iter()
            .map(|f| format!("--{f}"))
            .collect::<Vec<_>>()
            .join(" × ")
    }

    /// One line for `--help` and `info`: the flags, the range, and what binds it.
    pub fn line(&self) -> String {
        format!(
            "{:<20} {}..={}: {}",
            self.name(),
            self.range.start(),
            self.range.end(),
            self.binds
        )
    }
}

/// Every bound, in the order [`RenderNumbers::check`] checks them; the segments' with
/// the geometry resident, or streamed through a pool (`--pool-mb`).
pub fn bounds(streamed: bool) -> [Bound; 8] {
    let binding = binding_bytes();
    let scene = SceneLimits::default();
    let texture = wgpu::Limits::default().max_texture_dimension_2d;
    let (list, list_bytes) = binding_light_list();
    let square = max_pixels().isqrt();
    let side = |flag| Bound {
        flags: flag,
        range: 1..=max_side(),
        binds: format!(
            "the image is a 2-D texture of at most {texture} texels a side (wgpu's default max_texture_dimension_2d)"
        ),
        fix: "change --width/--height",
    };
    [
        Bound {
            flags: &["segments"],
            range: segments(streamed),
            binds: match streamed {
                true => format!(
                    "streamed through --pool-mb, only the mesh's roots and culling data stay resident: `bake`'s range of {}..={} (16 × segments² triangles)",
                    BAKED_SEGMENTS.start(),
                    BAKED_SEGMENTS.end()
                ),
                false => format!(
                    "resident, the procedural mesh (16 × segments² triangles) and the field's ground share the scene's payload binding of {} words ({binding} bytes, wgpu's default max_storage_buffer_binding_size); streamed with --pool-mb, up to {}",
                    scene.max_payload_words,
                    BAKED_SEGMENTS.end()
                ),
            },
            fix: match streamed {
                true => "use fewer segments",
                false => "use fewer segments, or stream the mesh through a pool with --pool-mb",
            },
        },
        Bound {
            flags: &["instances"],
            range: 0..=max_instances(),
            binds: format!(
                "the instance table takes at most two storage bindings of {binding} bytes (max_storage_buffer_binding_size): {} records of {} bytes, one of them the field's ground",
                scene.max_instances, INSTANCE.size
            ),
            fix: "place fewer copies",
        },
        Bound {
            flags: &["lights"],
            range: 0..=max_lights(),
            binds: format!(
                "the light clustering's {list} grows with the lights and is bound whole: one more light makes it {list_bytes} bytes, past the storage binding of {binding} bytes (max_storage_buffer_binding_size)"
            ),
            fix: "use fewer lights",
        },
        side(&["width"]),
        side(&["height"]),
        Bound {
            flags: &["width", "height"],
            range: 1..=max_pixels(),
            binds: format!(
                "the visibility buffer holds {} bytes a pixel in one storage binding of {binding} bytes (max_storage_buffer_binding_size): {square} × {square}, or {} × {} at most",
                Element::U64.size,
                max_side(),
                max_pixels() / max_side(),
            ),
            fix: "render fewer pixels: lower --width or --height",
        },
        Bound {
            flags: &["clusters"],
            range: 1..=max_clusters(),
            binds: format!(
                "the candidate list holds at least one cluster and at most one storage binding of {}-byte records",
                CLUSTER.size
            ),
            fix: "it grows by itself when a frame overflows it, so the default is a fine start",
        },
        Bound {
            flags: &["slots"],
            range: 1..=max_slots(),
            binds: format!(
                "the raster slots hold at least one cluster and at most one storage binding of {}-byte records (and 2^25, the slot bits of a visibility id)",
                CLUSTER.size
            ),
            fix: "they grow by themselves when a frame overflows them",
        },
    ]
}

/// The bounds as `render --help` and `info` print them, a line each (the segments'
/// with the geometry resident; their line gives the streamed range).
pub fn lines() -> Vec<String> {
    bounds(false).iter().map(Bound::line).collect()
}

/// What `render --help` says after the flags.
pub fn help() -> String {
    let mut text = String::from(
        "Bounds (what the renderer holds with wgpu's default limits, which every device meets; checked before a mesh is baked or an adapter is asked for):\n",
    );
    for line in lines() {
        text.push_str("  ");
        text.push_str(&line);
        text.push('\n');
    }
    text
}

/// A number `meshlight render` refuses: the flags, what was asked, the range it must lie
/// in, the limit that binds it, and what to change.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{given} is outside {min}..={max}: {why}")]
pub struct OutOfRange {
    /// The bounded flags, without their dashes (two for the pixel count).
    pub flags: &'static [&'static str],
    /// The flags as given, e.g. `--lights 5` or `--width 8192 --height 8192 (67108864
    /// pixels)`.
    pub given: String,
    /// The number checked: the flag's, or the product of the flags'.
    pub requested: u64,
    pub min: u64,
    pub max: u64,
    /// The limit that binds, and what to change.
    pub why: String,
}

/// The numbers of one `render` command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RenderNumbers {
    pub segments: u32,
    pub instances: u32,
    pub lights: u32,
    pub width: u32,
    pub height: u32,
    pub clusters: Option<u64>,
    pub slots: Option<u64>,
    /// The geometry streams through a pool (`--pool-mb`), so only its roots and culling
    /// data are resident.
    pub streamed: bool,
}

impl Default for RenderNumbers {
    /// What `meshlight render` draws with no flags: the default scene at 1280×720.
    fn default() -> Self {
        Self {
            segments: meshlight::scene::DEFAULT_SEGMENTS,
            instances: meshlight_virtual_geometry::scenes::DEFAULT_INSTANCES,
            lights: meshlight_virtual_geometry::scenes::DEFAULT_LIGHTS,
            width: 1280,
            height: 720,
            clusters: None,
            slots: None,
            streamed: false,
        }
    }
}

impl RenderNumbers {
    /// The numbers of the scene options `render` and `view` share, with `render`'s
    /// `--clusters` and `--slots` where given.
    pub fn of_scene(
        scene: &meshlight_virtual_geometry::SceneOptions,
        clusters: Option<u64>,
        slots: Option<u64>,
    ) -> Self {
        Self {
            segments: scene.segments,
            instances: scene.instances,
            lights: scene.lights_asked(),
            width: scene.width,
            height: scene.height,
            clusters,
            slots,
            streamed: scene.pool_mb.is_some(),
        }
    }

    /// The numbers [`bounds`] bounds, in its order: `None` where a flag is not given.
    fn given(&self) -> [Option<u64>; 8] {
        [
            Some(self.segments.into()),
            Some(self.instances.into()),
            Some(self.lights.into()),
            Some(self.width.into()),
            Some(self.height.into()),
            Some(u64::from(self.width) * u64::from(self.height)),
            self.clusters,
            self.slots,
        ]
    }

    /// How the command line gave the flags of `bound`, for an error about `value`.
    fn spelled(&self, bound: &Bound, value: u64) -> String {
        match bound.flags {
            ["width", "height"] => format!(
                "--width {} --height {} ({value} pixels)",
                self.width, self.height
            ),
            flags => format!("--{} {value}", flags.join(" --")),
        }
    }

    /// The first number outside its bound, in the order of [`bounds`].
    pub fn check(&self) -> Result<(), OutOfRange> {
        for (bound, value) in bounds(self.streamed).into_iter().zip(self.given()) {
            match value {
                Some(requested) if !bound.range.contains(&requested) => {
                    return Err(OutOfRange {
                        flags: bound.flags,
                        given: self.spelled(&bound, requested),
                        requested,
                        min: *bound.range.start(),
                        max: *bound.range.end(),
                        why: format!("{}; {}", bound.binds, bound.fix),
                    });
                }
                _ => {}
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The defaults pass; every bound's printed line comes from the list the check uses.
    #[test]
    fn the_defaults_pass_and_the_printed_bounds_are_the_checked_ones() {
        assert_eq!(RenderNumbers::default().check(), Ok(()));
        let printed = help();
        for bound in bounds(false) {
            let range = format!("{}..={}", bound.range.start(), bound.range.end());
            assert!(printed.contains(&bound.name()), "{printed}");
            assert!(printed.contains(&range), "{range}: {printed}");
        }
    }

    /// A number that overflows u32 when multiplied is still refused, not wrapped.
    #[test]
    fn the_largest_numbers_are_refused_without_overflow() {
        let n = RenderNumbers {
            lights: u32::MAX,
            ..RenderNumbers::default()
        };
        assert_eq!(n.check().unwrap_err().flags, &["lights"]);
        let n = RenderNumbers {
            width: u32::MAX,
            height: u32::MAX,
            ..RenderNumbers::default()
        };
        assert_eq!(n.check().unwrap_err().flags, &["width"]);
    }
}
