//! The sample-count evaluation of §4.3.3 (`shaders/adaptive-ssaa/evaluate.wgsl`, CPU twin
//! [`crate::cpu::evaluate`]).

use ::gpu::PassTimer;

use super::Ssaa;

impl Ssaa {
    /// Evaluates the metrics into the sample counts (needs `S`).
    pub fn encode_evaluate(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.dispatch(encoder, &self.pipelines.evaluate, timer, "evaluate");
    }
}
