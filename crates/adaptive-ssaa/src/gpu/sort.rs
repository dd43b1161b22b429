//! The sorted resolve of §4.3.5 (`shaders/adaptive-ssaa/sort.wgsl`): the image of
//! [`crate::cpu::shade::shade_adaptive`], with pixels grouped by sample count.

use ::gpu::PassTimer;
use ::gpu::kernel::{Passes, Workgroups};

use super::Ssaa;

impl Ssaa {
    /// The sorted resolve (§4.3.5): histogram of the sample counts, scan (which also writes
    /// the indirect dispatch), scatter of the pixels by count, shading of the sorted list.
    pub(super) fn encode_sorted(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&PassTimer>,
    ) {
        encoder.clear_buffer(&self.sort, 0, None);
        self.dispatch(encoder, &self.pipelines.sort_count, timer, "sort count");
        let groups = vec![self.group.clone(), self.args_group.clone()];
        let scan = Workgroups::Direct([1, 1, 1]);
        Passes::one("sort scan", &self.pipelines.sort_scan, groups, scan).encode(encoder, timer);
        self.dispatch(encoder, &self.pipelines.sort_scatter, timer, "sort scatter");
        let sorted = Workgroups::Indirect(self.args.clone(), 0);
        Passes::one(
            "shade sorted",
            &self.pipelines.shade_sorted,
            vec![self.group.clone()],
            sorted,
        )
        .encode(encoder, timer);
    }
}
