//! The LOD threshold coupled to how much of the pool the view wants.
//!
//! When the pages a view wants outgrow the pool, something must give. Evicting pages
//! still in use would make the streamer reload them the next frame (thrashing), so
//! instead the cut itself is made coarser: the pixel-error threshold is scaled up while
//! the wanted bytes are above a high mark, and back down while they are below a low
//! mark. A full pool costs detail, never correctness: the cut is complete at any scale.
//!
//! The band between the marks must be wider than one step's effect, or the scale would
//! swing between them. Wanted bytes go roughly with the inverse square of the threshold
//! (a surface's triangles per pixel), so one step of `s` changes them by `s²`: the
//! default step of 1.05 moves them by 10 %, inside the 70–85 % band.

/// The scale of the LOD threshold, raised under pool pressure and relaxed without it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LodPressure {
    /// Above this fraction of the pool wanted, the scale rises one step a frame.
    pub high: f32,
    /// Below this fraction, it falls one step a frame (never under 1).
    pub low: f32,
    /// The factor of one step.
    pub step: f32,
    /// The largest scale: past it the view wants more than the pool even at its
    /// coarsest, and the cut falls back to what is resident.
    pub max_scale: f32,
    /// Frames without running out of room before the scale may fall again.
    pub calm_frames: u32,
    scale: f32,
    /// Frames since a wanted page last found no room.
    calm: u32,
}

impl Default for LodPressure {
    /// A 70–85 % band, steps of 5 %, up to 64× the threshold.
    fn default() -> Self {
        Self::new(0.70, 0.85, 1.05, 64.0)
    }
}

impl LodPressure {
    /// A band from `low` to `high` (fractions of the pool), steps of `step`, at scale 1.
    pub fn new(low: f32, high: f32, step: f32, max_scale: f32) -> Self {
        Self {
            high,
            low,
            step,
            max_scale,
            calm_frames: 32,
            scale: 1.0,
            calm: u32::MAX,
        }
    }

    /// The factor the LOD threshold is multiplied by: 1 without pressure.
    pub fn scale(&self) -> f32 {
        self.scale
    }

    /// One frame's step, from the fraction of the pool the view wants; returns the new
    /// scale.
    pub fn update(&mut self, wanted_fraction: f32) -> f32 {
        self.update_with_room(wanted_fraction, false)
    }

    /// [`Self::update`], also told whether a wanted page found no room this frame. The
    /// wanted bytes do not count every page the view needs (a resident page's ancestors
    /// are held by it, not wanted), so a pool may be full of needed pages below the high
    /// mark: running out of room raises the scale as passing the mark does, and the
    /// scale then falls only after `calm_frames` frames with room, so it does not swing
    /// between the two.
    pub fn update_with_room(&mut self, wanted_fraction: f32, out_of_room: bool) -> f32 {
        self.calm = match out_of_room {
            true => 0,
            false => self.calm.saturating_add(1),
        };
        if out_of_room || wanted_fraction > self.high {
            self.scale = (self.scale * self.step).min(self.max_scale);
        } else if wanted_fraction < self.low && self.calm >= self.calm_frames {
            self.scale = (self.scale / self.step).max(1.0);
        }
        self.scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pressure_raises_the_scale_and_its_absence_relaxes_it_with_a_dead_band() {
        let mut p = LodPressure::default();
        assert_eq!(p.update(0.5), 1.0);
        let raised = (0..10).map(|_| p.update(0.9)).last().unwrap();
        assert!((raised - 1.05f32.powi(10)).abs() < 1e-4, "{raised}");
        // Inside the band the scale holds.
        assert_eq!(p.update(0.8), raised);
        assert_eq!(p.update(0.71), raised);
        for _ in 0..100 {
            p.update(0.1);
        }
        assert_eq!(p.scale(), 1.0);
        for _ in 0..1000 {
            p.update(2.0);
        }
        assert_eq!(p.scale(), 64.0);
    }

    /// Running out of room raises the scale below the high mark, and it falls back only
    /// after the calm frames.
    #[test]
    fn running_out_of_room_raises_the_scale_and_it_relaxes_only_after_calm_frames() {
        let mut p = LodPressure::default();
        assert_eq!(p.update_with_room(0.75, false), 1.0);
        assert_eq!(p.update_with_room(0.75, true), 1.05);
        assert_eq!(p.update_with_room(0.75, true), 1.05 * 1.05);
        // Below the low mark, but not yet calm: held.
        let held = p.scale();
        for _ in 0..p.calm_frames - 1 {
            assert_eq!(p.update_with_room(0.5, false), held);
        }
        assert!(p.update_with_room(0.5, false) < held);
    }

    /// With wanted bytes going as 1/scale², the scale settles inside the band instead of
    /// swinging across it.
    #[test]
    fn a_view_that_wants_twice_the_pool_settles_inside_the_band() {
        let mut p = LodPressure::default();
        let wanted = |scale: f32| 2.0 / (scale * scale);
        let mut scales = Vec::new();
        for _ in 0..200 {
            let s = p.scale();
            scales.push(p.update(wanted(s)));
        }
        let last = *scales.last().unwrap();
        assert!(scales[150..].iter().all(|&s| s == last), "{scales:?}");
        assert!((0.70..=0.85).contains(&wanted(last)), "{}", wanted(last));
    }
}
