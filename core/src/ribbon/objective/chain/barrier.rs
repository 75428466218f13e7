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
        let n = model.segments;
        model.terminal_penalty = match face {
            Some((range, rho)) => {
                assert_eq!(
                    range,
                    model.c_index(1)..model.c_index(n - 1) + 1,
                    "the chain's only slab is the crease differences' sum"
                );
                rho
            }
            None => 0.0,
        };
        self.mask.clear();
        self.mask.resize(model.dimension(), true);
        model.factor(&self.mask, shift)
    }

    fn solve_shifted(&mut self, rhs: &[f64], out: &mut [f64]) -> bool {
        self.model.solve(rhs, out)
    }
}
