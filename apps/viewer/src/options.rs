//! What the viewer is asked for: the scene and graph of `meshlight render`, plus the
//! window's own choices (`meshlight view --help` describes each).

use glam::Vec3;
use meshlight_virtual_geometry::SceneOptions;
use std::path::PathBuf;

/// The viewer's options; `meshlight view` parses them from its command line.
#[derive(Clone, Debug)]
pub struct ViewerOptions {
    /// The scene, its graph and the window's first size, as `meshlight render` takes
    /// them. A pipeline file is watched: saving it rebuilds the frame, and an error in
    /// it is shown while the last good graph keeps rendering. The view is the one shown
    /// first (changed live in the overlay).
    pub scene: SceneOptions,
    /// Exit after this many frames (with --screenshot, the last one is written).
    pub frames: Option<u64>,
    /// Write the last frame's image (the graph's `color`, without the overlay) as PNG.
    pub screenshot: Option<PathBuf>,
    /// A fixed camera, `x,y,z:tx,ty,tz` (position and target), instead of the scene's.
    pub camera: Option<CameraSpec>,
    /// A scripted camera: one revolution around the scene's target every this many
    /// frames (for demos and timing runs; input still works on top).
    pub orbit_frames: Option<u32>,
    /// No overlay: the window shows the frame alone.
    pub no_overlay: bool,
    /// Present without waiting for the display (for timing runs).
    pub no_vsync: bool,
}

impl ViewerOptions {
    /// The defaults of the command line at a given size.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            scene: SceneOptions::new(width, height),
            frames: None,
            screenshot: None,
            camera: None,
            orbit_frames: None,
            no_overlay: false,
            no_vsync: false,
        }
    }
}

/// A camera position and the point it looks at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSpec {
    pub position: Vec3,
    pub target: Vec3,
}

impl CameraSpec {
    /// Reads `x,y,z:tx,ty,tz`.
    pub fn parse(text: &str) -> Result<Self, String> {
        let vec = |part: &str| -> Result<Vec3, String> {
            let v: Vec<f32> = part
                .split(',')
                .map(|n| n.trim().parse::<f32>())
                .collect::<Result<_, _>>()
                .map_err(|e| format!("`{part}`: {e}"))?;
            match v[..] {
                [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(x, y, z)),
                _ => Err(format!("`{part}`: three finite numbers x,y,z expected")),
            }
        };
        let (p, t) = text
            .split_once(':')
            .ok_or_else(|| format!("`{text}`: write the camera as x,y,z:tx,ty,tz"))?;
        let (position, target) = (vec(p)?, vec(t)?);
        if position.distance(target) < 1e-6 {
            return Err(format!("`{text}`: the camera must not sit on its target"));
        }
        Ok(Self { position, target })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_specs_read_and_refuse() {
        let c = CameraSpec::parse("1, 2,3:0,0.5,-4").expect("valid");
        assert_eq!(c.position, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(c.target, Vec3::new(0.0, 0.5, -4.0));
        for bad in [
            "1,2,3",
            "1,2:0,0,0",
            "1,2,3:1,2,3",
            "a,b,c:0,0,0",
            "1,2,inf:0,0,0",
        ] {
            assert!(CameraSpec::parse(bad).is_err(), "{bad} accepted");
        }
    }
}
