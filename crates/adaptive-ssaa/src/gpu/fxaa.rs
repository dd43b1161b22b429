//! The FXAA baseline on `S` (`shaders/adaptive-ssaa/fxaa.wgsl`, CPU twin [`crate::cpu::fxaa`]).

use ::gpu::PassTimer;

use super::Ssaa;

impl Ssaa {
    /// FXAA on `S` into the output (needs `S`).
    pub fn encode_fxaa(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.dispatch(encoder, &self.pipelines.fxaa, timer, "fxaa");
    }
}
