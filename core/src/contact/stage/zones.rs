//! The impact-zone QP of a round (Harmon et al. 2008): the step's constraint set, its
//! split into zones of bodies linked by a constraint, and each zone's dual QP solved
//! with the bodies' pre-factorized closeness metrics.

use super::ContactStage;

impl ContactStage {
    /// Add the detected contacts to the step's constraint set (both sorted by key).
    /// Constraints are never dropped within a step (impact zones only grow, Harmon et
    /// al.): a contact detected again is added as another cutting plane when its old
    /// linearization let it be violated beyond the tolerance, so the rounds cannot
    /// cycle between linearizations (nearly parallel edges slide their closest
    /// points from round to round).
    pub(super) fn merge_detected(&mut self) {
        if self.detected.is_empty() {
            return;
        }
        let tol = self.settings.tolerance;
        self.merged.clear();
        let (mut i, mut j) = (0, 0);
        let (old, new) = (&self.constraints, &self.detected);
        while i < old.len() || j < new.len() {
            if j >= new.len() || (i < old.len() && old[i].key <= new[j].key) {
                let key = old[i].key;
                // every old constraint of this key, then the new one if still violated
                while i < old.len() && old[i].key == key {
                    self.merged.push(old[i]);
                    i += 1;
                }
                if j < new.len() && new[j].key == key {
                    if new[j].distance - new[j].gap(&self.x) > tol {
                        self.merged.push(new[j]);
                    }
                    j += 1;
                }
            } else {
                self.merged.push(new[j]);
                j += 1;
            }
        }
        std::mem::swap(&mut self.constraints, &mut self.merged);
    }

    /// Solve the QP of all constraints from `self.target` into `self.x`; returns the
    /// active-set changes.
    pub(super) fn solve_qp(&mut self) -> u32 {
        let nb = self.bodies.len();
        let m = self.constraints.len();
        self.lambda.clear();
        self.lambda.resize(m, 0.0);
        // zones: union-find over bodies linked by a constraint
        for (i, z) in self.zone_of_body.iter_mut().enumerate() {
            *z = i;
        }
        fn find(z: &mut [usize], mut i: usize) -> usize {
            while z[i] != i {
                z[i] = z[z[i]];
                i = z[i];
            }
            i
        }
        for c in &self.constraints {
            let mut root = None;
            for k in 0..c.count as usize {
                let g = c.vertices[k] as usize;
                if g >= self.unknowns {
                    continue;
                }
                let b = self.body_of(g);
                let r = find(&mut self.zone_of_body, b);
                match root {
                    None => root = Some(r),
                    Some(r0) if r0 != r => {
                        let (lo, hi) = (r0.min(r), r0.max(r));
                        self.zone_of_body[hi] = lo;
                        root = Some(lo);
                    }
                    _ => {}
                }
            }
        }
        for b in 0..nb {
            let r = find(&mut self.zone_of_body, b);
            self.zone_of_body[b] = r;
        }
        // x = X~ on the unknowns, then each zone adds H^-1 C^T λ
        self.x[..self.unknowns].copy_from_slice(&self.target[..self.unknowns]);
        let mut iterations = 0;
        for zone in 0..nb {
            if self.zone_of_body[zone] != zone {
                continue;
            }
            self.zone_constraints.clear();
            for (ci, c) in self.constraints.iter().enumerate() {
                let g = c.vertices[..c.count as usize]
                    .iter()
                    .map(|&g| g as usize)
                    .find(|&g| g < self.unknowns);
                if let Some(g) = g {
                    if self.zone_of_body[self.body_of(g)] == zone {
                        self.zone_constraints.push(ci);
                    }
                }
            }
            if !self.zone_constraints.is_empty() {
                iterations += self.solve_zone();
            }
        }
        iterations
    }
    /// The dual QP of the constraints in `self.zone_constraints`: columns z_c =
    /// H_s^-1 w_c, the dual system (A, b), the active-set solve, then x += Σ_c λ_c z_c
    /// n_c^T. Returns the active-set changes.
    fn solve_zone(&mut self) -> u32 {
        let m = self.zone_constraints.len();
        self.assign_columns();
        let body_offset = self.solve_columns();
        self.assemble_dual(&body_offset);
        self.dual_lambda.clear();
        self.dual_lambda.resize(m, 0.0);
        let outcome = self.qp.solve(
            &self.dual_a,
            &self.dual_b,
            &mut self.dual_lambda,
            0.1 * self.settings.tolerance,
            self.settings.max_qp_iterations,
        );
        self.apply_zone_multipliers(&body_offset);
        self.body_offset = body_offset;
        outcome.iterations
    }

    /// Columns z_c = H_s^-1 w_c per body touched by c, batched per body: for each zone
    /// constraint, (body, column index within the body) of up to two bodies in
    /// `self.column_of`, and each body's zone constraints in `self.body_columns`.
    fn assign_columns(&mut self) {
        let m = self.zone_constraints.len();
        for cols in self.body_columns.iter_mut() {
            cols.clear();
        }
        self.column_of.clear();
        self.column_of.resize(m, [(u32::MAX, 0); 2]);
        for (zi, &ci) in self.zone_constraints.iter().enumerate() {
            let c = &self.constraints[ci];
            let mut slot = 0;
            for k in 0..c.count as usize {
                let g = c.vertices[k] as usize;
                if g >= self.unknowns {
                    continue;
                }
                let b = self.body_of(g);
                if self.column_of[zi][..slot]
                    .iter()
                    .any(|&(bb, _)| bb as usize == b)
                {
                    continue;
                }
                self.column_of[zi][slot] = (b as u32, self.body_columns[b].len() as u32);
                self.body_columns[b].push(zi);
                slot += 1;
            }
        }
    }

    /// The columns themselves: body b's contiguous, N_b x m_b column-major in
    /// `self.columns` from the returned offset of b on, each the weights w_c solved
    /// with the body's pre-factorized metric.
    fn solve_columns(&mut self) -> Vec<usize> {
        let mut total = 0usize;
        let mut body_offset = std::mem::take(&mut self.body_offset);
        body_offset.clear();
        body_offset.resize(self.bodies.len(), 0);
        for (b, body) in self.bodies.iter().enumerate() {
            body_offset[b] = total;
            total += body.topology.vertices * self.body_columns[b].len();
        }
        self.columns.clear();
        self.columns.resize(total, 0.0);
        for (b, body) in self.bodies.iter_mut().enumerate() {
            let n = body.topology.vertices;
            let cols = &self.body_columns[b];
            if cols.is_empty() {
                continue;
            }
            let block = &mut self.columns[body_offset[b]..body_offset[b] + n * cols.len()];
            for (j, &zi) in cols.iter().enumerate() {
                let c = &self.constraints[self.zone_constraints[zi]];
                for k in 0..c.count as usize {
                    let g = c.vertices[k] as usize;
                    if g >= body.first && g < body.first + n {
                        block[j * n + (g - body.first)] += c.weights[k];
                    }
                }
            }
            body.metric.solve_in_place(block, cols.len());
        }
        body_offset
    }

    /// The dual system: A_cd = (n_c . n_d) Σ_{i in d} w_i z_c[i] (symmetrized against
    /// rounding) in `self.dual_a`, b_c = distance - gap(X~) (m) in `self.dual_b`.
    fn assemble_dual(&mut self, body_offset: &[usize]) {
        let m = self.zone_constraints.len();
        self.dual_a.clear();
        self.dual_a.resize(m * m, 0.0);
        self.dual_b.clear();
        for (ci_z, &ci) in self.zone_constraints.iter().enumerate() {
            let c = &self.constraints[ci];
            self.dual_b.push(c.distance - c.gap(&self.target));
            for (di_z, &di) in self.zone_constraints.iter().enumerate() {
                let d = &self.constraints[di];
                let mut s = 0.0;
                for k in 0..d.count as usize {
                    let g = d.vertices[k] as usize;
                    if g >= self.unknowns {
                        continue;
                    }
                    let b = self.body_of(g);
                    for &(bb, j) in &self.column_of[ci_z] {
                        if bb as usize == b {
                            let n = self.bodies[b].topology.vertices;
                            let idx = body_offset[b] + j as usize * n + (g - self.bodies[b].first);
                            s += d.weights[k] * self.columns[idx];
                        }
                    }
                }
                self.dual_a[ci_z * m + di_z] = s * c.normal.dot(&d.normal);
            }
        }
        // symmetrize (rounding)
        for i in 0..m {
            for j in 0..i {
                let v = 0.5 * (self.dual_a[i * m + j] + self.dual_a[j * m + i]);
                self.dual_a[i * m + j] = v;
                self.dual_a[j * m + i] = v;
            }
        }
    }

    /// The zone's multipliers into `self.lambda` and the primal correction
    /// x += Σ_c λ_c z_c n_c^T (m) into `self.x`.
    fn apply_zone_multipliers(&mut self, body_offset: &[usize]) {
        for (zi, &ci) in self.zone_constraints.iter().enumerate() {
            let l = self.dual_lambda[zi];
            self.lambda[ci] = l;
            if l == 0.0 {
                continue;
            }
            let n = self.constraints[ci].normal;
            for &(b, j) in &self.column_of[zi] {
                if b == u32::MAX {
                    continue;
                }
                let body = &self.bodies[b as usize];
                let nv = body.topology.vertices;
                let col = &self.columns[body_offset[b as usize] + j as usize * nv..][..nv];
                for (i, z) in col.iter().enumerate() {
                    if *z != 0.0 {
                        self.x[body.first + i] += n * (l * z);
                    }
                }
            }
        }
    }
}
