//! The shading stages of §4.3.4 (`shaders/adaptive-ssaa/shade.wgsl`, CPU twin
//! [`crate::cpu::shade`]): `S`, the adaptive resolve of Listing 4.1 and full supersampling.

use ::gpu::PassTimer;

use super::Ssaa;
use crate::Resolve;

impl Ssaa {
    /// Shades the first sample per pixel into `S`.
    pub fn encode_first(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.dispatch(encoder, &self.pipelines.first, timer, "shade first");
    }

    /// Shades the remaining samples into the output with the configured [`Resolve`].
    pub fn encode_resolve(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        match self.config.resolve {
            Resolve::Loop => {
                self.dispatch(encoder, &self.pipelines.adaptive, timer, "shade adaptive")
            }
            Resolve::Sorted => self.encode_sorted(encoder, timer),
            Resolve::Tiles => self.dispatch(encoder, &self.pipelines.tiles, timer, "shade tiles"),
        }
    }

    /// Full supersampling into the output (the reference).
    pub fn encode_full(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.dispatch(encoder, &self.pipelines.full, timer, "shade full");
    }
}
