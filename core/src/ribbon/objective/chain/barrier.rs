//! The chain model as the interior-point method's matrix (issue 47): the barrier's
//! diagonal Σ + δ_w per unknown goes into the sweep's per-unknown shift, and the slab's
//! rank-one term ρ a a^T is a penalty on the terminal value c_{n-1} = Σ z_k.

use super::ChainMatrix;

impl crate::optim::BarrierMatrix for ChainMatrix {
    fn factor_shifted(
        &mut self,
        shift: &[f64],
        face: Option<(std::ops::Range<usize>, f64)>,
    ) -> bool {
        let model = &mut self.model;
        model.hold_slab_face(face);
        self.mask.clear();
        self.mask.resize(model.dimension(), true);
        model.factor(&self.mask, shift)
    }

    fn solve_shifted(&mut self, rhs: &[f64], out: &mut [f64]) -> bool {
        self.model.solve(rhs, out)
    }
}
