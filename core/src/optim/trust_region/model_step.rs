//! The model step of one trust-region iteration, on the model only (no evaluation of
//! f): the generalized Cauchy point along the projected gradient path, then subspace
//! rounds on the unknowns strictly inside the region: an undamped Newton step where the
//! model is positive definite there, else the step with the least shift that makes it
//! so, each followed by a projected search on the model.

use super::{ModelMatrix, ModelStep, TrustRegion, INSIDE_EPS, MAX_ROUNDS, MU0};

/// A free unknown the direction pushes through the region's bound before this fraction
/// of the search's first trial is put on that bound (see
/// `TrustRegion::binding_direction`).
const BINDING: f64 = 0.01;
/// Extrapolations of the Cauchy point's t (by 10) and of a shifted step (by 2).
const CAUCHY_EXTRAPOLATIONS: usize = 20;
const SHIFTED_EXTRAPOLATIONS: usize = 12;
/// Rounds of binding before a subspace round's direction is kept.
const BIND_ROUNDS: usize = 2;
/// The search for the least positive-definite shift starts at this fraction of the
/// last one (consecutive models are alike, and a lower shift gives the longer step).
const SHIFT_RESTART: f64 = 0.25;

/// How a subspace round's direction was found.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Direction {
    /// The Newton step on the free set (the model's minimizer on that face).
    Newton,
    /// The step of the model with the least shift sigma I that makes it positive
    /// definite (where it is not): its components along the directions of negative
    /// curvature are the longest (1 / (lambda + sigma)), so the search follows it to
    /// the region's boundary and beyond, each unknown stopping at its own bound.
    Shifted,
}

impl<M: ModelMatrix> TrustRegion<M> {
    /// m(s) = g.s + ½ s.Hs from s and Hs.
    pub(super) fn model(&self, s: &[f64], hs: &[f64]) -> f64 {
        s.iter()
            .zip(hs)
            .zip(&self.g)
            .map(|((si, hi), gi)| si * (gi + 0.5 * hi))
            .sum()
    }

    /// The model step into `self.s` (and H s into `self.hs`): the generalized Cauchy
    /// point, then subspace rounds while they add bounds; the best point of them.
    pub(super) fn model_step(&mut self, x: &[f64]) -> ModelStep {
        self.cauchy_point(x);
        self.round_shift = None;
        self.indefinite = false;
        self.best_s.copy_from_slice(&self.s);
        self.best_hs.copy_from_slice(&self.hs);
        let mut best = self.model(&self.s, &self.hs);
        for _ in 0..MAX_ROUNDS {
            let more = self.subspace_round(x);
            let m = self.model(&self.s, &self.hs);
            if m < best {
                best = m;
                self.best_s.copy_from_slice(&self.s);
                self.best_hs.copy_from_slice(&self.hs);
            }
            if !more {
                break;
            }
        }
        // (a round that put unknowns on their bounds can end above an earlier one)
        self.s.copy_from_slice(&self.best_s);
        self.hs.copy_from_slice(&self.best_hs);
        let on_boundary = (0..x.len()).any(|i| {
            let reach = self.radius * self.units[i];
            self.s[i].abs() >= (1.0 - 1e-9) * reach
        });
        ModelStep {
            predicted: -best,
            on_boundary,
        }
    }

    /// `self.point`, a step from x, made feasible: x + point projected onto the region
    /// and the slab.
    fn project_step(&mut self, x: &[f64]) {
        let mut p = std::mem::take(&mut self.point);
        for i in 0..x.len() {
            p[i] += x[i];
        }
        match &self.slab {
            Some(slab) => {
                // (points of one path are near: the last multiplier starts the search)
                self.path_tau = slab.project(&mut p, &self.lo, &self.hi, self.path_tau);
            }
            None => {
                for i in 0..p.len() {
                    p[i] = p[i].clamp(self.lo[i], self.hi[i]);
                }
            }
        }
        for i in 0..x.len() {
            p[i] -= x[i];
        }
        self.point = p;
    }

    /// `self.point` = P(x + (s if `from_s`) + t w) - x, P onto the region and the slab,
    /// `self.h_point` = H of it; returns the model there. One product H v.
    fn path_point(&mut self, x: &[f64], from_s: bool, t: f64) -> f64 {
        for i in 0..x.len() {
            let base = if from_s { self.s[i] } else { 0.0 };
            self.point[i] = base + t * self.w[i];
        }
        self.project_step(x);
        self.products += 1;
        self.h.multiply(&self.point, &mut self.h_point);
        self.model(&self.point, &self.h_point)
    }

    /// s = the last path point, H s = H of it.
    fn keep_point(&mut self) {
        self.s.copy_from_slice(&self.point);
        self.hs.copy_from_slice(&self.h_point);
    }

    /// Whether the path point at t satisfies the Cauchy point's sufficient decrease,
    /// m(s(t)) <= μ0 g.s(t) (with g.s(t) < 0).
    fn cauchy_sufficient(&mut self, x: &[f64], t: f64) -> bool {
        let m = self.path_point(x, false, t);
        let gs: f64 = self.point.iter().zip(&self.g).map(|(a, b)| a * b).sum();
        gs < 0.0 && m <= MU0 * gs
    }

    /// The generalized Cauchy point: s(t) = P(x - t g) - x with m(s(t)) <= μ0 g.s(t),
    /// t extrapolated by 10 while that holds and s(t) still moves, else backtracked
    /// by 10 (Lin and Moré 1999). Starts from the last iteration's t, or from the t at
    /// which the steepest-descent step reaches the radius. s stays 0 if none passes.
    /// It fixes the unknowns the subspace rounds start with on their bounds.
    fn cauchy_point(&mut self, x: &[f64]) {
        let n = x.len();
        let mut t = self.cauchy_t;
        if !(t > 0.0) {
            let reach = (0..n)
                .map(|i| self.g[i].abs() / self.units[i])
                .fold(0.0, f64::max);
            t = self.radius / reach.max(1e-300);
        }
        for i in 0..n {
            self.w[i] = -self.g[i];
        }
        self.s.fill(0.0);
        self.hs.fill(0.0);
        if self.cauchy_sufficient(x, t) {
            self.keep_point();
            for _ in 0..CAUCHY_EXTRAPOLATIONS {
                let next = 10.0 * t;
                if !self.cauchy_sufficient(x, next) || self.point == self.s {
                    break;
                }
                t = next;
                self.keep_point();
            }
        } else {
            for _ in 0..20 {
                t *= 0.1;
                if self.cauchy_sufficient(x, t) {
                    self.keep_point();
                    break;
                }
            }
        }
        self.cauchy_t = t;
    }

    /// Whether x_i + step_i is strictly inside the region.
    fn inside(&self, x: &[f64], step: &[f64], i: usize) -> bool {
        let y = x[i] + step[i];
        let tol = INSIDE_EPS * (1.0 + y.abs());
        y > self.lo[i] + tol && y < self.hi[i] - tol
    }

    /// Whether x + `step` is on a face of the slab (false without one).
    fn on_face(&mut self, x: &[f64], step: &[f64]) -> bool {
        let Some(slab) = &self.slab else { return false };
        for i in slab.range.clone() {
            self.trial[i] = x[i] + step[i];
        }
        slab.face(&self.trial) != 0.0
    }

    /// One subspace round from s: the free set (strictly inside the region), a direction
    /// on it, a projected search on the model along it. Whether another round may help
    /// (the search stopped on a bound that was not active).
    fn subspace_round(&mut self, x: &[f64]) -> bool {
        let n = x.len();
        let mut largest: f64 = 0.0;
        for i in 0..n {
            self.free[i] = self.inside(x, &self.s, i);
            self.rhs[i] = if self.free[i] {
                -(self.g[i] + self.hs[i])
            } else {
                0.0
            };
            largest = largest.max(self.rhs[i].abs());
        }
        let s = std::mem::take(&mut self.s);
        let face_held = self.on_face(x, &s);
        self.s = s;
        if !(largest > 0.0) {
            return false;
        }
        let Some((direction, shift)) = self.binding_direction(x, face_held) else {
            return false;
        };
        let Some(t) = self.search(x, direction, shift, face_held) else {
            return false;
        };
        if direction == Direction::Shifted {
            self.extrapolate(x, t);
        }
        let point = std::mem::take(&mut self.point);
        let new_bound = (0..n).any(|i| self.free[i] && !self.inside(x, &point, i))
            || (!face_held && self.on_face(x, &point));
        self.point = point;
        self.keep_point();
        new_bound
    }

    /// The projected search on the model along `self.w` from s: the first t (from the
    /// search's start, then the path's first bend, then halving) with m(P(s + t w)) <=
    /// m(s) + μ0 r.(P(s + t w) - s), r = g + H s; the point and H of it in
    /// `self.point` and `self.h_point`. On the straight part of the path (before any
    /// unknown reaches its bound) the model is the parabola m(s) + t r.w + ½ t² w^T H w
    /// with w^T H w = -r.w - shift |w|² (w solves the shifted system on the free set,
    /// where a held face adds nothing: a.w = 0), so those trials cost no product.
    fn search(
        &mut self,
        x: &[f64],
        direction: Direction,
        shift: f64,
        face_held: bool,
    ) -> Option<f64> {
        let n = x.len();
        let m0 = self.model(&self.s, &self.hs);
        let slope: f64 = -(0..n).map(|i| self.rhs[i] * self.w[i]).sum::<f64>();
        let norm2: f64 = (0..n)
            .filter(|&i| self.free[i])
            .map(|i| self.w[i] * self.w[i])
            .sum();
        let curvature = -slope - shift * norm2;
        // where the path first bends: a free unknown reaches the region's bound, or the
        // sum the slab's face (where it is not held)
        let mut bend = (0..n)
            .filter(|&i| self.free[i] && self.w[i] != 0.0)
            .map(|i| {
                let y = x[i] + self.s[i];
                let room = if self.w[i] > 0.0 {
                    self.hi[i] - y
                } else {
                    y - self.lo[i]
                };
                room / self.w[i].abs()
            })
            .fold(f64::INFINITY, f64::min);
        if let Some(slab) = self.slab.as_ref().filter(|_| !face_held) {
            let sum: f64 = slab.range.clone().map(|i| x[i] + self.s[i]).sum();
            let rate: f64 = slab.range.clone().map(|i| self.w[i]).sum();
            if rate != 0.0 {
                let edge = slab.bound * rate.signum();
                bend = bend.min(((edge - sum) / rate).max(0.0));
            }
        }
        let mut t = self.search_start(direction);
        for trial in 0..30 {
            let (m, linear) = if t <= bend {
                (m0 + t * slope + 0.5 * t * t * curvature, true)
            } else {
                (self.path_point(x, true, t), false)
            };
            let moved = if linear {
                t * slope
            } else {
                (0..n)
                    .map(|i| (self.g[i] + self.hs[i]) * (self.point[i] - self.s[i]))
                    .sum()
            };
            if m < m0 && m <= m0 + MU0 * moved {
                if linear {
                    // the point and H of it: H s + t H w (one product)
                    self.products += 1;
                    self.h.multiply(&self.w, &mut self.h_point);
                    for i in 0..n {
                        self.point[i] = self.s[i] + t * self.w[i];
                        self.h_point[i] = self.hs[i] + t * self.h_point[i];
                    }
                }
                return Some(t);
            }
            t = if trial == 0 && bend > 0.0 && bend < t {
                bend
            } else {
                0.5 * t
            };
        }
        None
    }

    /// [`Self::direction`], with one round of binding: a free unknown that the
    /// direction would push through the region's bound within `BINDING` of the search's
    /// first trial is put on that bound (if that does not raise the model; else held
    /// where it is), and the direction found again without it. The projected search
    /// would clip it at once, bending the path until only a tiny step passes (seen as
    /// rounds that each added one bound at t ~ 1e-6 on the twisted strip).
    fn binding_direction(&mut self, x: &[f64], face_held: bool) -> Option<(Direction, f64)> {
        if self.shift > 0.0 {
            // the unknowns to bind from a step at the last shift (one factorization,
            // positive definite as a rule), then the least shift on what is left: the
            // bound unknowns are often where the negative curvature was
            let face = self.face_penalty(face_held);
            let mut binds = 0;
            loop {
                self.factorizations += 1;
                if !self.h.factor_free(&self.free, self.shift, face.clone()) {
                    break;
                }
                let Some(found) = self.step_at(self.shift, face.is_some()) else {
                    break;
                };
                if binds == BIND_ROUNDS || !self.bind(x, found.0) {
                    break;
                }
                binds += 1;
            }
            return self.direction(face_held, false);
        }
        let mut found = self.direction(face_held, false)?;
        for _ in 0..BIND_ROUNDS {
            if !self.bind(x, found.0) {
                break;
            }
            found = self.direction(face_held, true)?;
        }
        Some(found)
    }

    /// One round of binding for the direction in `self.w`: whether unknowns were bound
    /// (and free ones are left).
    fn bind(&mut self, x: &[f64], direction: Direction) -> bool {
        let n = x.len();
        let start = self.search_start(direction);
        let m_before = self.model(&self.s, &self.hs);
        self.point.copy_from_slice(&self.s);
        let mut bound = false;
        for i in 0..n {
            if !self.free[i] || self.w[i] == 0.0 {
                continue;
            }
            let y = x[i] + self.s[i];
            let (room, edge) = if self.w[i] > 0.0 {
                (self.hi[i] - y, self.hi[i])
            } else {
                (y - self.lo[i], self.lo[i])
            };
            if room < BINDING * start * self.w[i].abs() {
                self.point[i] = edge - x[i];
                self.free[i] = false;
                bound = true;
            }
        }
        if !bound || !self.free.iter().any(|&f| f) {
            return false;
        }
        // (and back into the slab)
        self.project_step(x);
        self.products += 1;
        self.h.multiply(&self.point, &mut self.h_point);
        if self.model(&self.point, &self.h_point) <= m_before {
            self.keep_point();
        }
        for i in 0..n {
            self.rhs[i] = if self.free[i] {
                -(self.g[i] + self.hs[i])
            } else {
                0.0
            };
        }
        true
    }

    /// Where the search along `self.w` starts: the Newton step's full length, or where
    /// a shifted step's largest component reaches the region's boundary.
    fn search_start(&self, direction: Direction) -> f64 {
        match direction {
            Direction::Newton => 1.0,
            Direction::Shifted => {
                let reach = (0..self.w.len())
                    .map(|i| self.w[i].abs() / self.units[i])
                    .fold(0.0, f64::max);
                self.radius / reach.max(1e-300)
            }
        }
    }

    /// After a passed trial at t along a shifted step (in `self.point`): t doubled while
    /// the projected path's model keeps falling, the best point kept in `self.point`.
    fn extrapolate(&mut self, x: &[f64], mut t: f64) {
        let mut best = self.model(&self.point, &self.h_point);
        let mut kept = std::mem::take(&mut self.trial);
        let mut kept_h = std::mem::take(&mut self.face_solution);
        kept.copy_from_slice(&self.point);
        kept_h.copy_from_slice(&self.h_point);
        for _ in 0..SHIFTED_EXTRAPOLATIONS {
            t *= 2.0;
            let m = self.path_point(x, true, t);
            if !(m < best) || self.point == kept {
                break;
            }
            best = m;
            kept.copy_from_slice(&self.point);
            kept_h.copy_from_slice(&self.h_point);
        }
        self.point.copy_from_slice(&kept);
        self.h_point.copy_from_slice(&kept_h);
        self.trial = kept;
        self.face_solution = kept_h;
    }

    /// The direction of a subspace round into `self.w` (held entries 0), for the
    /// right-hand side -(g + H s) in `self.rhs`, and its shift: the Newton step on the
    /// free set (on the slab's face when `face_held`, exactly, by one more solve) where
    /// the model is positive definite there, else the step with the least shift sigma I
    /// (in the unknowns' units, not diag(H)) of a sequence that makes it so. `again`:
    /// the same round with fewer free unknowns (binding), whose shift stays positive
    /// definite (a principal submatrix). None if nothing works.
    fn direction(&mut self, face_held: bool, again: bool) -> Option<(Direction, f64)> {
        let face = self.face_penalty(face_held);
        // the same round with fewer free unknowns (binding): its shift again, positive
        // definite on a principal submatrix
        if let Some(shift) = self.round_shift.filter(|_| again) {
            self.factorizations += 1;
            if self.h.factor_free(&self.free, shift, face.clone()) {
                return self.step_at(shift, face.is_some());
            }
        }
        // undamped, where the model is positive definite on the free set (not tried
        // again in a later round of a model step whose first round was indefinite)
        if !self.indefinite {
            self.factorizations += 1;
            if self.h.factor_free(&self.free, 0.0, face.clone()) {
                self.round_shift = Some(0.0);
                return self.step_at(0.0, face.is_some());
            }
            self.indefinite = true;
        }
        // else the least shift: from a quarter of the last one (consecutive models are
        // alike), each failure raising it by twice the failing pivot's deficit, at least
        // doubling
        let largest = (0..self.free.len())
            .filter(|&i| self.free[i])
            .map(|i| self.diagonal[i].abs())
            .fold(0.0, f64::max);
        let floor = 1e-12 * largest.max(1e-300);
        let mut shift = (SHIFT_RESTART * self.shift).max(floor);
        for _ in 0..60 {
            self.factorizations += 1;
            if self.h.factor_free(&self.free, shift, face.clone()) {
                self.shift = shift;
                self.round_shift = Some(shift);
                return self.step_at(shift, face.is_some());
            }
            let deficit = self.h.failed_pivot().map_or(0.0, |l| -l);
            shift = (2.0 * shift).max(shift + 2.0 * deficit);
        }
        None
    }

    /// The step of the factorization at `shift` (the Newton step where it is 0).
    fn step_at(&mut self, shift: f64, on_face: bool) -> Option<(Direction, f64)> {
        let direction = if shift > 0.0 {
            Direction::Shifted
        } else {
            Direction::Newton
        };
        self.newton_step(on_face).then_some((direction, shift))
    }

    /// The slab's face as a penalty for the factorization where it is held: rho the
    /// largest diagonal entry of H on the free part of the slab's range.
    fn face_penalty(&self, face_held: bool) -> Option<(std::ops::Range<usize>, f64)> {
        let slab = self.slab.as_ref().filter(|_| face_held)?;
        let rho = slab
            .range
            .clone()
            .filter(|&i| self.free[i])
            .map(|i| self.diagonal[i].abs())
            .fold(0.0, f64::max);
        (rho > 0.0).then(|| (slab.range.clone(), rho))
    }

    /// w = the solve of the last factorization for `self.rhs`; on the slab's face
    /// (`on_face`), projected onto it exactly: w -= y (a.w) / (a.y), y the solve for the
    /// face's normal a (1 on the free entries of the range), so that a.w = 0 and w
    /// minimizes the model on the face (the penalty is zero there). False if not finite.
    fn newton_step(&mut self, on_face: bool) -> bool {
        if !self.h.solve_free(&self.rhs, &mut self.w) {
            return false;
        }
        if !on_face {
            return true;
        }
        let range = self.slab.as_ref().map(|s| s.range.clone()).unwrap_or(0..0);
        self.face_normal.fill(0.0);
        for i in range.clone() {
            if self.free[i] {
                self.face_normal[i] = 1.0;
            }
        }
        if !self
            .h
            .solve_free(&self.face_normal, &mut self.face_solution)
        {
            return false;
        }
        let (aw, ay) = range
            .clone()
            .filter(|&i| self.free[i])
            .fold((0.0, 0.0), |(a, b), i| {
                (a + self.w[i], b + self.face_solution[i])
            });
        if ay > 0.0 {
            let ratio = aw / ay;
            for (w, y) in self.w.iter_mut().zip(&self.face_solution) {
                *w -= y * ratio;
            }
        }
        self.w.iter().all(|w| w.is_finite())
    }
}
