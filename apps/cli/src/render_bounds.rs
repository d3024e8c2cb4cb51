//! Bounds on the numbers `meshlight render` takes, checked before a mesh is baked or an
//! adapter is requested. Each bound is what the renderer can hold on any device with
//! wgpu's default limits (the limits the scene data is sized for): a number past it
//! would otherwise exhaust memory on the CPU (`--lights 4294967295` asked for 275 GB)
//! or surface as a wgpu validation message naming no flag (`--clusters 0`).

use meshlight::gpu_scene::data::Limits as SceneLimits;
use meshlight::gpu_scene::gpu::elements::CLUSTER;
use meshlight::z_slice::{CLUSTERABLE_OBJECT, SLICE_INSTANCE};
use meshlight_light_clustering::ClusteringSettings;
use meshlight_virtual_geometry::frame_graph::MAX_SLOTS;
use std::ops::RangeInclusive;

/// Tube segments of the procedural mesh, the range `meshlight bake` takes: at least 3
/// for a closed tube, at most 1024 (16.7 M triangles).
pub const SEGMENTS: RangeInclusive<u64> = 3..=1024;

/// A number `meshlight render` refuses: the flag, what was asked, the range it must lie
/// in, and what limits it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("--{flag} {requested} is outside {min}..={max}: {why}")]
pub struct OutOfRange {
    pub flag: &'static str,
    pub requested: u64,
    pub min: u64,
    pub max: u64,
    /// What holds the number, and what to change.
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
}

/// The largest count of `element_size`-byte elements one binding holds with wgpu's
/// default limits (every buffer the renderer sizes from a flag is bound whole).
fn per_binding(element_size: u32) -> u64 {
    let limits = wgpu::Limits::default();
    limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size)
        / u64::from(element_size)
}

/// The most lights the frame's clustering can hold: its object list, the (object,
/// slice) list and the froxel entries are sized from the light count
/// ([`ClusteringSettings::new`]), and each is bound whole.
pub fn max_lights() -> u64 {
    let fits = |n: u64| {
        let s = ClusteringSettings::new([1, 1], n.max(1));
        s.objects <= per_binding(CLUSTERABLE_OBJECT.size)
            && s.slice_instances <= per_binding(SLICE_INSTANCE.size)
            && s.entries <= per_binding(4)
    };
    // The sizes grow with the count, so the largest that fits is found by bisection.
    let (mut lo, mut hi) = (0u64, u64::from(u32::MAX));
    while lo < hi {
        let mid = lo + (hi - lo).div_ceil(2);
        if fits(mid) { lo = mid } else { hi = mid - 1 }
    }
    lo
}

/// Instances the command line places at most, before the device is known: 4 Mi copies
/// (940 MB of instance records on the CPU). The device's own binding limit is checked
/// when the scene is built for the chosen adapter ([`meshlight::gpu_scene::data::Limits::for_device`]):
/// the instance table takes two bindings at most, 1,198,372 instance records with wgpu's
/// default 128 MiB binding, and a data-centre GPU binds far more.
pub const MAX_INSTANCES: u64 = 1 << 22;

/// The most copies of the mesh: [`MAX_INSTANCES`] less the field's ground.
pub fn max_instances() -> u64 {
    MAX_INSTANCES - 1
}

/// The largest side of the image: wgpu's default 2-D texture limit, which every device
/// meets (the renderer checks the adapter's own limit again).
pub fn max_side() -> u64 {
    u64::from(wgpu::Limits::default().max_texture_dimension_2d)
}

/// The largest candidate-cluster list (and raster-slot list, which visibility ids also
/// bound): one binding of cluster records.
pub fn max_clusters() -> u64 {
    per_binding(CLUSTER.size)
}

pub fn max_slots() -> u64 {
    max_clusters().min(MAX_SLOTS)
}

/// Every flag's bound, for `meshlight info`.
pub fn bounds() -> [(&'static str, RangeInclusive<u64>); 7] {
    [
        ("segments", SEGMENTS),
        ("instances", 0..=max_instances()),
        ("lights", 0..=max_lights()),
        ("width", 1..=max_side()),
        ("height", 1..=max_side()),
        ("clusters", 1..=max_clusters()),
        ("slots", 1..=max_slots()),
    ]
}

/// What holds the number a flag gives, and what to change when it is out of bounds.
fn why(flag: &str) -> String {
    let binding = wgpu::Limits::default().max_storage_buffer_binding_size;
    match flag {
        "segments" => "the procedural mesh has 16 × segments² triangles and needs 3 segments to close; `bake` takes the same range".into(),
        "instances" => format!(
            "the command line places at most {MAX_INSTANCES} instances (one is the ground), and the device's binding limit may allow fewer ({} in two of wgpu's default bindings of {binding} bytes); place fewer copies",
            SceneLimits::default().max_instances
        ),
        "lights" => format!(
            "the light clustering's object, slice and froxel lists grow with the light count and each must fit wgpu's default binding of {binding} bytes; use fewer lights"
        ),
        "width" | "height" => "an image side is at least 1 pixel and at most wgpu's default 2-D texture limit; change --width/--height".into(),
        "clusters" => format!(
            "the candidate list holds at least one cluster and at most one binding of {}-byte records; it grows by itself when a frame overflows it, so the default is a fine start",
            CLUSTER.size
        ),
        _ => format!(
            "the raster slots hold at least one cluster and at most one binding of {}-byte records (and 2^25, the slot bits of a visibility id); they grow by themselves when a frame overflows them",
            CLUSTER.size
        ),
    }
}

impl RenderNumbers {
    /// The first number outside its bound, in the order of [`bounds`].
    pub fn check(&self) -> Result<(), OutOfRange> {
        let given = [
            Some(self.segments.into()),
            Some(self.instances.into()),
            Some(self.lights.into()),
            Some(self.width.into()),
            Some(self.height.into()),
            self.clusters,
            self.slots,
        ];
        for ((flag, bound), value) in bounds().into_iter().zip(given) {
            match value {
                Some(requested) if !bound.contains(&requested) => {
                    return Err(OutOfRange {
                        flag,
                        requested,
                        min: *bound.start(),
                        max: *bound.end(),
                        why: why(flag),
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

    fn defaults() -> RenderNumbers {
        RenderNumbers {
            segments: meshlight::scene::DEFAULT_SEGMENTS,
            instances: meshlight_virtual_geometry::scenes::DEFAULT_INSTANCES,
            lights: meshlight_virtual_geometry::scenes::DEFAULT_LIGHTS,
            width: 1280,
            height: 720,
            clusters: None,
            slots: None,
        }
    }

    /// Sets one flag's number.
    type Set = fn(&mut RenderNumbers, u64);

    #[test]
    fn the_defaults_pass_and_each_bound_is_its_edge() {
        assert_eq!(defaults().check(), Ok(()));
        let max_lights = u32::try_from(max_lights()).unwrap();
        let max_instances = u32::try_from(max_instances()).unwrap();
        let max_side = u32::try_from(max_side()).unwrap();
        let cases: [(&str, u64, u64, Set); 7] = [
            ("segments", 3, 1024, |n, v| n.segments = v as u32),
            ("instances", 0, max_instances.into(), |n, v| {
                n.instances = v as u32
            }),
            ("lights", 0, max_lights.into(), |n, v| n.lights = v as u32),
            ("width", 1, max_side.into(), |n, v| n.width = v as u32),
            ("height", 1, max_side.into(), |n, v| n.height = v as u32),
            ("clusters", 1, max_clusters(), |n, v| n.clusters = Some(v)),
            ("slots", 1, max_slots(), |n, v| n.slots = Some(v)),
        ];
        for (flag, min, max, set) in cases {
            for ok in [min, max] {
                let mut n = defaults();
                set(&mut n, ok);
                assert_eq!(n.check(), Ok(()), "--{flag} {ok}");
            }
            let mut outside = vec![max + 1];
            if min > 0 {
                outside.push(min - 1);
            }
            for bad in outside {
                let mut n = defaults();
                set(&mut n, bad);
                let e = n.check().unwrap_err();
                assert_eq!(
                    (e.flag, e.requested, e.min, e.max),
                    (flag, bad, min, max),
                    "{e}"
                );
            }
        }
    }

    /// The light bound is where the clustering's lists stop fitting, and it is far
    /// below the count that asked for 275 GB.
    #[test]
    fn the_light_bound_is_the_largest_count_whose_lists_fit() {
        let max = max_lights();
        let lists = |n: u64| {
            let s = ClusteringSettings::new([1, 1], n);
            [
                s.objects * u64::from(CLUSTERABLE_OBJECT.size),
                s.slice_instances * u64::from(SLICE_INSTANCE.size),
                s.entries * 4,
            ]
        };
        let binding = wgpu::Limits::default().max_storage_buffer_binding_size;
        assert!(lists(max).iter().all(|&b| b <= binding), "{max}");
        assert!(lists(max + 1).iter().any(|&b| b > binding), "{max}");
        assert!((100_000..u64::from(u32::MAX)).contains(&max), "{max}");
    }
}
