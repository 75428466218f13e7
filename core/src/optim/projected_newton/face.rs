//! The one slab |Σ_S x_i| <= b besides the box ([`Slab`]) in the projected Newton
//! method (issue 47's `solver.end_crease_exact` for the chain solver): the projection
//! onto box and slab, the projected gradient with it, and the Newton step held on a face.

use super::{NewtonMatrix, ProjectedNewton, Slab};
use crate::optim::slab::project_feasible;

impl<M: NewtonMatrix> ProjectedNewton<M> {
    /// Hold one slab |Σ_S x_i| <= b besides the box in the next solves (None: the box
    /// alone): the start, every trial point and the projected gradient are projected
    /// onto box and slab ([`Slab::project`]); where x is on a face and the Newton step
    /// would cross it, the step is the model's minimizer on the face (one more solve
    /// with the same factorization).
    pub fn set_slab(&mut self, slab: Option<Slab>) {
        self.slab = slab;
    }

    /// `y` projected onto [lower, upper] and the slab (if any).
    pub(super) fn project(&self, y: &mut [f64], lower: &[f64], upper: &[f64]) {
        project_feasible(self.slab.as_ref(), y, lower, upper);
    }

    /// ||P(x - g) - x||_inf, P onto box and slab; sets `slab_tau`.
    pub(super) fn projected_gradient(&mut self, x: &[f64], lower: &[f64], upper: &[f64]) -> f64 {
        let (norm, tau) = crate::optim::slab::projected_gradient(
            self.slab.as_ref(),
            (x, &self.g),
            (lower, upper),
            &mut self.point,
        );
        self.slab_tau = tau;
        norm
    }

    /// Where x is on a face of the slab and the step in `self.reduced` crosses it: the
    /// model's minimizer on the face instead, d - ν w with w = H_FF^{-1} a (a the
    /// slab's indicator on the free set) and ν = a.d / a.w, so that a.d = 0 (the same
    /// factorization, one more solve). False if that solve fails.
    pub(super) fn hold_face(&mut self, x: &[f64]) -> bool {
        let Some(slab) = &self.slab else { return true };
        let face = slab.face(x);
        let range = slab.range.clone();
        if face == 0.0 {
            return true;
        }
        let across: f64 = self
            .free
            .iter()
            .zip(&self.reduced)
            .filter(|(i, _)| range.contains(i))
            .map(|(_, d)| d)
            .sum();
        // held where the gradient pushes through the face (τ in P(x - g) has its
        // sign), as a box bound is held by its gradient, whatever the step does (held
        // where the step crosses it instead: 3-8x the iterations at n = 400, 800)
        if !(self.slab_tau * face > 0.0) || across == 0.0 {
            return true;
        }
        let mut w = std::mem::take(&mut self.face_w);
        w.clear();
        w.extend(
            self.free
                .iter()
                .map(|i| if range.contains(i) { 1.0 } else { 0.0 }),
        );
        let ok = self.h.solve(&self.free, &mut w);
        let aw: f64 = self
            .free
            .iter()
            .zip(&w)
            .filter(|(i, _)| range.contains(i))
            .map(|(_, v)| v)
            .sum();
        let ok = ok && aw > 0.0;
        if ok {
            let nu = across / aw;
            for (d, wi) in self.reduced.iter_mut().zip(&w) {
                *d -= nu * wi;
            }
        }
        self.face_w = w;
        ok
    }
}
