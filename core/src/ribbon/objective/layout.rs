//! Where each generalized coordinate lives in q = <w, t | c_1..c_{n-1} | psi_1..psi_{n-1}>,
//! and packing coordinates into q and back.

use crate::geometry::{exp_so3, Pose, Vector3};
use crate::ribbon::reconstruct::Coordinates;

/// Where each generalized coordinate lives in q.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    pub segments: usize,
    pub floating: bool,
}

impl Layout {
    /// Number of base coordinates (6 for a floating base: rotation vector, translation).
    #[inline]
    pub fn base_len(&self) -> usize {
        if self.floating {
            6
        } else {
            0
        }
    }
    /// Index of c_k (k = 1..n-1).
    #[inline]
    pub fn c(&self, k: usize) -> usize {
        self.base_len() + k - 1
    }
    /// Index of psi_k (k = 1..n-1).
    #[inline]
    pub fn psi(&self, k: usize) -> usize {
        self.base_len() + self.segments - 1 + k - 1
    }
    pub fn len(&self) -> usize {
        self.base_len() + 2 * (self.segments - 1)
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The first element a coordinate moves (s_a): 0 for the base, k for c_k and psi_k.
    #[inline]
    pub fn first_element(&self, a: usize) -> usize {
        let b = self.base_len();
        if a < b {
            0
        } else {
            let k = (a - b) % (self.segments - 1);
            k + 1
        }
    }

    /// Pack coordinates into q. A floating base is stored relative to `reference`:
    /// R = exp(w) R_ref, so w stays small (exact Newton curvature at w = 0, no
    /// rotation-vector singularity at |w| = pi) when the reference is the last state.
    pub fn pack(&self, coords: &Coordinates, reference: &Pose, q: &mut [f64]) {
        if self.floating {
            let w = (coords.base.rotation * reference.rotation.inverse()).scaled_axis();
            let t = coords.base.translation.vector;
            q[0..3].copy_from_slice(w.as_slice());
            q[3..6].copy_from_slice(t.as_slice());
        }
        for k in 1..self.segments {
            q[self.c(k)] = coords.crease_direction[k];
            q[self.psi(k)] = coords.bending_angle[k];
        }
    }

    /// Unpack q into coordinates (a prescribed base keeps `coords.base`; a floating
    /// one is exp(w) R_ref with `reference`'s rotation).
    pub fn unpack(&self, q: &[f64], reference: &Pose, coords: &mut Coordinates) {
        if self.floating {
            let w = Vector3::new(q[0], q[1], q[2]);
            let t = Vector3::new(q[3], q[4], q[5]);
            let r = nalgebra::Rotation3::from_matrix_unchecked(exp_so3(&w));
            let r = nalgebra::UnitQuaternion::from_rotation_matrix(&r) * reference.rotation;
            coords.base = Pose::from_parts(t.into(), r);
        }
        for k in 1..self.segments {
            coords.crease_direction[k] = q[self.c(k)];
            coords.bending_angle[k] = q[self.psi(k)];
        }
        coords.crease_direction[0] = 0.0;
        coords.crease_direction[self.segments] = 0.0;
    }
}
