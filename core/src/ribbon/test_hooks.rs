//! Test-only hooks of [`RibbonSim`] (`test-hooks` feature, on in the crate's own
//! dev-dependency only): the negative controls of the solver comparisons
//! (tests/ribbon_chain_solver.rs).

use super::RibbonSim;

impl RibbonSim {
    /// Test-only (`test-hooks` feature): the chain solvers' Newton matrix made subtly
    /// wrong, every crease's 2x2 block scaled by 1 + `relative` (the objective and its
    /// gradient stay exact), for the negative controls of the solver comparisons.
    #[cfg(any(test, feature = "test-hooks"))]
    pub fn set_newton_matrix_error(&mut self, relative: f64) {
        self.solver.newton_matrix_error = relative;
    }

    /// Test-only (`test-hooks` feature): the chain solver's loop closure always in the
    /// 14-column Woodbury form (the form before 2026-12-07; docs/ribbon_chain_solver.md),
    /// for the negative control of the loop solver comparisons.
    #[cfg(any(test, feature = "test-hooks"))]
    pub fn set_fourteen_column_closure(&mut self, on: bool) {
        self.solver.fourteen_column_closure = on;
    }
}
