//! Texture views by (texture, range), created once and kept while frames use them, so bind
//! groups over the same view are found in the cache frame after frame.

use crate::record::physical::{EVICT_AFTER_FRAMES, range_view, whole_view};
use crate::resource::TextureRange;
use std::collections::HashMap;

#[derive(Default)]
pub(crate) struct ViewCache {
    views: HashMap<(wgpu::Texture, Option<TextureRange>), (wgpu::TextureView, u64)>,
}

impl ViewCache {
    pub fn begin_frame(&mut self, frame: u64) {
        self.views
            .retain(|_, (_, last)| frame.saturating_sub(*last) <= EVICT_AFTER_FRAMES);
    }
    /// The view of every mip and layer.
    pub fn whole(&mut self, texture: &wgpu::Texture, frame: u64) -> wgpu::TextureView {
        self.get(texture, None, frame)
    }
    pub fn range(
        &mut self,
        texture: &wgpu::Texture,
        range: TextureRange,
        frame: u64,
    ) -> wgpu::TextureView {
        self.get(texture, Some(range), frame)
    }
    fn get(
        &mut self,
        texture: &wgpu::Texture,
        range: Option<TextureRange>,
        frame: u64,
    ) -> wgpu::TextureView {
        let entry = self
            .views
            .entry((texture.clone(), range))
            .or_insert_with(|| {
                let view = match range {
                    Some(r) => range_view(texture, r),
                    None => whole_view(texture),
                };
                (view, frame)
            });
        entry.1 = frame;
        entry.0.clone()
    }
}
