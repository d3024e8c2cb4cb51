//! The overlay: frame times as a rolling chart, the frame's counters, the thresholds,
//! the debug view and the implementation of every stage that has several, and the last
//! error. It only reads the viewer's state and returns what the user asked for; the
//! viewer applies it after the frame.

use crate::camera::CameraRig;
use crate::viewer::FrameTime;
use meshlight::graph::FrameStats;
use meshlight::resolve::DebugView;
use meshlight_virtual_geometry::{FrameSettings, Renderer};
use std::collections::VecDeque;
use std::path::Path;

/// What the overlay shows, borrowed from the viewer for one frame.
pub struct Facts<'a> {
    pub renderer: &'a Renderer,
    pub settings: &'a FrameSettings,
    pub times: &'a VecDeque<FrameTime>,
    pub stats: Option<&'a FrameStats>,
    pub error: Option<&'a str>,
    /// Stage, its implementations, the one running.
    pub choices: Vec<(String, Vec<String>, String)>,
    pub pipeline: Option<&'a Path>,
    pub rig: &'a CameraRig,
}

/// What the user changed this frame.
#[derive(Default, Debug)]
pub struct OverlayActions {
    pub view: Option<DebugView>,
    pub thresholds: Option<(f32, f32)>,
    pub implementation: Option<(String, String)>,
}

/// The sliders' values while they are dragged (applied on release, as each apply
/// rebuilds the graph).
#[derive(Default)]
pub struct Overlay {
    lod_px: Option<f32>,
    sw_px: Option<f32>,
}

/// One line about each view, shown under the drop-down.
pub fn legend(view: DebugView) -> &'static str {
    match view {
        DebugView::Shaded => "lit surface (textured or checkered) over a sky gradient",
        DebugView::Clusters => "a colour per rasterised cluster",
        DebugView::Triangles => "a colour per triangle",
        DebugView::Lod => "a colour per LOD level of the pixel's meshlet",
        DebugView::Raster => "which rasteriser drew the pixel: software or hardware",
        DebugView::Depth => "reverse-Z depth as grey, depth^(1/4)",
        DebugView::LightCount => "lights per froxel: black none, red 32 or more",
        DebugView::Pyramid => "a mip of the depth pyramid as grey",
        DebugView::Material => "a colour per material",
        DebugView::Uv => "texture coordinates: red fract(u), green fract(v)",
        DebugView::Normal => "the shading normal (normal map applied), n/2 + 1/2",
        DebugView::Mip => "a colour per mip level of the base colour texture",
        DebugView::BaseColor => "base colour (factor x texture), unlit",
        DebugView::Occlusion => {
            "green: first culling pass drew it, blue: second; red: share occluded"
        }
        DebugView::Residency => {
            "green: at the wanted level; yellow, orange, red: 1, 2, 3+ levels coarser (page not in the pool)"
        }
        DebugView::Shadow => {
            "sun shadow cascades: red, green, blue, yellow from the nearest; dark where shadowed"
        }
    }
}

impl Overlay {
    pub fn draw(&mut self, ui: &mut egui::Ui, f: &Facts<'_>) -> OverlayActions {
        let mut actions = OverlayActions::default();
        egui::Window::new("meshlight")
            .default_pos([8.0, 8.0])
            .default_width(300.0)
            .show(ui.ctx(), |ui| {
                self.times(ui, f);
                ui.separator();
                self.counters(ui, f);
                ui.separator();
                self.controls(ui, f, &mut actions);
                if let Some(e) = f.error {
                    ui.separator();
                    ui.colored_label(egui::Color32::from_rgb(255, 110, 90), e);
                }
            });
        actions
    }

    fn times(&self, ui: &mut egui::Ui, f: &Facts<'_>) {
        let last = f.times.back().copied().unwrap_or_default();
        let gpu = f
            .times
            .iter()
            .rev()
            .find_map(|t| t.gpu_ms)
            .map_or_else(|| "–".to_string(), |g| format!("{g:.2} ms"));
        ui.label(format!(
            "CPU {:.2} ms   GPU {gpu}   {}×{}",
            last.cpu_ms, f.settings.width, f.settings.height
        ));
        let (rect, _) =
            ui.allocate_exact_size(egui::vec2(ui.available_width(), 60.0), egui::Sense::hover());
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 2.0, egui::Color32::from_black_alpha(120));
        let top = f
            .times
            .iter()
            .map(|t| t.cpu_ms.max(t.gpu_ms.unwrap_or(0.0)))
            .fold(1.0f32, f32::max);
        let n = crate::viewer::HISTORY as f32;
        let point = |i: usize, ms: f32| {
            egui::pos2(
                rect.left() + rect.width() * i as f32 / n,
                rect.bottom() - rect.height() * (ms / top).min(1.0),
            )
        };
        let cpu: Vec<egui::Pos2> = f
            .times
            .iter()
            .enumerate()
            .map(|(i, t)| point(i, t.cpu_ms))
            .collect();
        let gpu: Vec<egui::Pos2> = f
            .times
            .iter()
            .enumerate()
            .filter_map(|(i, t)| t.gpu_ms.map(|g| point(i, g)))
            .collect();
        painter.add(egui::Shape::line(
            cpu,
            egui::Stroke::new(1.0, egui::Color32::from_rgb(120, 200, 255)),
        ));
        painter.add(egui::Shape::line(
            gpu,
            egui::Stroke::new(1.0, egui::Color32::from_rgb(255, 190, 80)),
        ));
        ui.label(format!("blue CPU, orange GPU; top {top:.1} ms"));
    }

    fn counters(&self, ui: &mut egui::Ui, f: &Facts<'_>) {
        if let Some(c) = f.renderer.latest_counts() {
            ui.label(format!(
                "{} clusters visible, {} triangles rasterised",
                c.visible,
                u64::from(c.software_triangles) + u64::from(c.hardware_triangles)
            ));
            egui::CollapsingHeader::new("counters").show(ui, |ui| {
                egui::Grid::new("counts").show(ui, |ui| {
                    for (label, value) in c.rows() {
                        ui.label(label);
                        ui.label(value.to_string());
                        ui.end_row();
                    }
                });
            });
        }
        if f.renderer.culls_in_two_passes() {
            let policy = f.settings.occlusion_policy;
            ui.label(if f.renderer.tests_occlusion() || policy.always() {
                "occlusion: tested".to_string()
            } else {
                format!(
                    "occlusion: left out (culled under {:.0} % of the cut), probed every {} frames",
                    policy.min_hidden * 100.0,
                    policy.probe_every
                )
            });
        }
        if let Some(s) = f.stats {
            ui.label(format!(
                "frame {}  graph CPU {:.2} ms  in flight {}",
                s.frame,
                s.cpu_frame_us / 1000.0,
                s.frames_in_flight
            ));
        }
        if let Some(s) = &f.renderer.streaming {
            let stats = s.stats();
            let frame = &stats.frame;
            ui.label(format!(
                "streaming: pool {:.0} of {:.0} MiB, LOD scale {:.2}",
                frame.pool_used as f64 / (1u64 << 20) as f64,
                frame.pool_bytes as f64 / (1u64 << 20) as f64,
                frame.lod_scale
            ));
            egui::CollapsingHeader::new("streaming").show(ui, |ui| {
                egui::Grid::new("streaming").show(ui, |ui| {
                    for (label, value) in stats.rows() {
                        ui.label(label);
                        ui.label(value);
                        ui.end_row();
                    }
                });
            });
        }
        let p = f.rig.position;
        ui.label(format!(
            "camera {:.2}, {:.2}, {:.2}  speed {:.2}{}",
            p.x,
            p.y,
            p.z,
            f.rig.speed,
            if f.rig.orbit { "  (orbit)" } else { "" }
        ));
    }

    fn controls(&mut self, ui: &mut egui::Ui, f: &Facts<'_>, actions: &mut OverlayActions) {
        let s = f.settings;
        let shown = f.renderer.view;
        let mut view = shown;
        egui::ComboBox::from_label("view")
            .selected_text(view.name())
            .show_ui(ui, |ui| {
                for v in DebugView::ALL {
                    ui.selectable_value(&mut view, v, v.name());
                }
            });
        ui.small(legend(view));
        if view != shown {
            actions.view = Some(view);
        }
        let (lod_now, sw_now) = f.renderer.thresholds();
        let mut lod = self.lod_px.unwrap_or(s.lod_threshold_px.unwrap_or(lod_now));
        let mut sw = self.sw_px.unwrap_or(s.sw_threshold_px.unwrap_or(sw_now));
        let lod_slider = ui.add(
            egui::Slider::new(&mut lod, 0.1..=16.0)
                .logarithmic(true)
                .text("LOD px"),
        );
        // Up to the largest split any adapter class uses: every cluster to software.
        let sw_slider = ui.add(
            egui::Slider::new(&mut sw, 0.0..=meshlight::cull_lod::EVERY_CLUSTER_PX)
                .logarithmic(true)
                .text("sw/hw split px"),
        );
        self.lod_px = Some(lod);
        self.sw_px = Some(sw);
        let released = lod_slider.drag_stopped()
            || sw_slider.drag_stopped()
            || (lod_slider.changed() && !lod_slider.dragged())
            || (sw_slider.changed() && !sw_slider.dragged());
        if released {
            actions.thresholds = Some((lod, sw));
            self.lod_px = None;
            self.sw_px = None;
        } else if !lod_slider.dragged() && !sw_slider.dragged() {
            self.lod_px = None;
            self.sw_px = None;
        }
        for (stage, names, current) in &f.choices {
            let mut picked = current.clone();
            egui::ComboBox::from_label(stage.as_str())
                .selected_text(picked.as_str())
                .show_ui(ui, |ui| {
                    for n in names {
                        ui.selectable_value(&mut picked, n.clone(), n.as_str());
                    }
                });
            if &picked != current {
                actions.implementation = Some((stage.clone(), picked));
            }
        }
        ui.small("WASD/QE fly, right drag look, scroll speed, O orbit, R reset, P/F12 screenshot, H report, T trace");
    }
}
