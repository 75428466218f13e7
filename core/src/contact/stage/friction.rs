//! Coulomb friction against colliders, applied to a round's converged positions.

use super::ContactStage;
use crate::contact::detect::Contact;
use crate::geometry::{Point3, Vector3};

impl ContactStage {
    /// Coulomb friction of the active collider contacts: the tangential motion of the
    /// contact point relative to the collider is cancelled when it is at most μ times
    /// the normal correction (stick), else reduced by that much (slip). Returns true
    /// when positions changed.
    pub(super) fn apply_friction(&mut self) -> bool {
        let mut changed = false;
        for (ci, c) in self.constraints.iter().enumerate() {
            let Some(k) = c.collider else { continue };
            let mu = self.colliders[k as usize].friction;
            if mu == 0.0 || self.lambda.get(ci).copied().unwrap_or(0.0) <= 0.0 {
                continue;
            }
            let n = c.normal;
            // ribbon side: the unknowns of the constraint; σ: sign of their weights
            let mut sum_w = 0.0;
            let mut sum_w2 = 0.0;
            let mut push = Vector3::zeros();
            let mut moved = Vector3::zeros();
            let mut obstacle = Vector3::zeros();
            let mut sum_k = 0.0;
            for i in 0..c.count as usize {
                let g = c.vertices[i] as usize;
                let w = c.weights[i];
                if g < self.unknowns {
                    sum_w += w;
                    sum_w2 += w * w;
                    push += (self.x[g] - self.target[g]) * w;
                    moved += (self.x[g] - self.x0[g]) * w;
                } else {
                    sum_k += w;
                    obstacle += (self.x[g] - self.x0[g]) * w;
                }
            }
            if sum_w2 == 0.0 {
                continue;
            }
            let sigma = sum_w.signum();
            let delta_n = n.dot(&push); // >= 0: how far the contact pushed the ribbon out
            if delta_n <= 0.0 {
                continue;
            }
            // motion of the obstacle at the contact point
            let obstacle_motion = if sum_k != 0.0 {
                obstacle * sum_k.signum()
            } else {
                // a solid: the motion of its material point under the contact point
                let p = self.contact_point(c);
                let k = k as usize;
                let p0 = self.poses0[k] * self.poses1[k].inverse_transform_point(&Point3::from(p));
                p - p0.coords
            };
            let relative = moved * sigma - obstacle_motion;
            let tangential = relative - n * n.dot(&relative);
            let t_len = tangential.norm();
            if t_len == 0.0 {
                continue;
            }
            let correction = if t_len <= mu * delta_n {
                -tangential
            } else {
                -tangential * (mu * delta_n / t_len)
            };
            for i in 0..c.count as usize {
                let g = c.vertices[i] as usize;
                if g < self.unknowns {
                    self.x[g] += correction * (sigma * c.weights[i] / sum_w2);
                }
            }
            changed = true;
        }
        changed
    }

    /// The ribbon-side contact point of a constraint at the current positions.
    fn contact_point(&self, c: &Contact) -> Vector3 {
        let mut p = Vector3::zeros();
        let mut sw = 0.0;
        for i in 0..c.count as usize {
            let g = c.vertices[i] as usize;
            if g < self.unknowns {
                p += self.x[g] * c.weights[i];
                sw += c.weights[i];
            }
        }
        p / sw
    }
}
