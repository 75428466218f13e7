//! The previous step's rims (X^n, V^n at their material stations) and the kinetic term
//! with the material-space resampling operator R (Pan et al. sec. 4, eq. 4), full
//! (consistent trapezoid mass, appendix B) or lumped on the centerline.

use super::accumulate::{point_jacobian, sliding_rate, Accumulator};
use super::{Mat8, Objective};
use crate::geometry::{skew, Matrix3, Point3, Vector3};
use crate::ribbon::mass::{element_mass, lumped_centerline_mass};
use crate::ribbon::reconstruct::{Frames, Strip};

/// X^n and V^n of the previous step on both rims, with the material stations u (m)
/// they sit at: the data the resampling operator R (eq. 4) interpolates.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RimHistory {
    /// Material coordinate along the rim of each bottom vertex, m (increasing).
    pub u_bottom: Vec<f64>,
    pub u_top: Vec<f64>,
    /// World positions, m (as vectors from the world origin).
    pub x_bottom: Vec<Vector3>,
    pub x_top: Vec<Vector3>,
    /// Velocities, m/s.
    pub v_bottom: Vec<Vector3>,
    pub v_top: Vec<Vector3>,
}

impl RimHistory {
    /// The history of a ribbon at rest in `frames` with creases `c`.
    pub fn at_rest(strip: &Strip, c: &[f64], frames: &Frames) -> Self {
        let n = strip.segments;
        RimHistory {
            u_bottom: (0..=n).map(|j| strip.material_bottom(j, c[j]).x).collect(),
            u_top: (0..=n).map(|j| strip.material_top(j, c[j]).x).collect(),
            x_bottom: frames.rim_bottom.iter().map(|p| p.coords).collect(),
            x_top: frames.rim_top.iter().map(|p| p.coords).collect(),
            v_bottom: vec![Vector3::zeros(); n + 1],
            v_top: vec![Vector3::zeros(); n + 1],
        }
    }
}

/// Piecewise-linear interpolation on a rim: value and slope d/du at station `u`.
#[inline]
pub(crate) fn interpolate<T>(us: &[f64], values: &[T], u: f64, hint: usize) -> (T, T)
where
    T: Copy
        + std::ops::Sub<Output = T>
        + std::ops::Mul<f64, Output = T>
        + std::ops::Add<Output = T>,
{
    let (k, inv_span, offset) = rim_segment(us, u, hint);
    interpolate_on(values, k, inv_span, offset)
}

/// The segment k with us[k] <= u < us[k+1] (clamped to the ends), 1 / (us[k+1] - us[k])
/// and u - us[k]: what every interpolation at `u` on this rim shares (the kinetic term
/// interpolates positions and velocities at the same station).
#[inline]
fn rim_segment(us: &[f64], u: f64, hint: usize) -> (usize, f64, f64) {
    // walking from `hint`: a new rim vertex sits next to the old one of the same index
    // (the crease bounds keep it within one element), so this is O(1) and the kinetic
    // term stays O(n).
    let last = us.len() - 2;
    let mut k = hint.min(last);
    while k > 0 && u < us[k] {
        k -= 1;
    }
    while k < last && u >= us[k + 1] {
        k += 1;
    }
    (k, 1.0 / (us[k + 1] - us[k]), u - us[k])
}

/// Value and slope of `values` on segment k (from [`rim_segment`]).
#[inline]
fn interpolate_on<T>(values: &[T], k: usize, inv_span: f64, offset: f64) -> (T, T)
where
    T: Copy
        + std::ops::Sub<Output = T>
        + std::ops::Mul<f64, Output = T>
        + std::ops::Add<Output = T>,
{
    let slope = (values[k + 1] - values[k]) * inv_span;
    (values[k] + slope * offset, slope)
}

impl Objective<'_> {
    /// Full kinetic term with resampling: rho/2 |(X - R(X̄, X^n))/h - R(X̄, V^n)|_M^2.
    pub(super) fn kinetic_full(
        &self,
        acc: &mut Accumulator,
        [res_b, res_t]: [&mut Vec<Vector3>; 2],
        [slope_b, slope_t]: [&mut Vec<Vector3>; 2],
    ) -> f64 {
        let n = self.strip.segments;
        let t = self.terms;
        let h = t.h;
        // (multiplications by 1/h, not divisions: this loop is a third of an evaluation)
        let inv_h = 1.0 / h;
        let w = self.strip.width;
        self.kinetic_residuals(
            acc.frames,
            &acc.coords.crease_direction,
            [res_b, res_t],
            [slope_b, slope_t],
        );
        let c = &acc.coords.crease_direction;
        let mut value = 0.0;
        for e in 0..n {
            let mass = element_mass(self.strip.length, w, n, c[e + 1] - c[e]);
            let verts = [(e, false), (e, true), (e + 1, false), (e + 1, true)];
            let d = [res_b[e], res_t[e], res_b[e + 1], res_t[e + 1]];
            let mut gamma = [Vector3::zeros(); 4];
            for a in 0..4 {
                for b in 0..4 {
                    gamma[a] += d[b] * (t.density * mass.k[a][b]);
                }
                value += 0.5 * d[a].dot(&gamma[a]);
            }
            if !acc.forces {
                // f alone (a backtracking trial): nothing below changes it
                continue;
            }
            // explicit mass dependence on Δc = c_{e+1} - c_e
            let mut dmass = 0.0;
            for a in 0..4 {
                for b in 0..4 {
                    dmass += 0.5 * t.density * mass.dk_ddelta_c[a][b] * d[a].dot(&d[b]);
                }
            }
            acc.add_local(e, -dmass, dmass);
            // per vertex: world position and the sliding column σ_a of dD_a/dc_j (zero
            // for the fixed end creases), for the Gauss-Newton block
            let mut xs = [Vector3::zeros(); 4];
            let mut sigma = [Vector3::zeros(); 4];
            let mut column = [None::<usize>; 4];
            for (a, &(j, top)) in verts.iter().enumerate() {
                let x = if top {
                    acc.frames.rim_top[j]
                } else {
                    acc.frames.rim_bottom[j]
                };
                let mat = if top {
                    self.strip.material_top(j, c[j])
                } else {
                    self.strip.material_bottom(j, c[j])
                };
                // dD/dX = I/h: the point gradient is gamma/h; the resampling slope adds a
                // local term on c_j.
                let slope = if top { slope_t[j] } else { slope_b[j] };
                let du = sliding_rate(w, top);
                acc.add_point_gradient(e, &mat, &x, &(gamma[a] * inv_h), Some((j, du)));
                xs[a] = x.coords;
                if j != 0 && j != n {
                    let local_extra = gamma[a].dot(&slope) * du;
                    if j == e {
                        acc.add_local(e, local_extra, 0.0);
                    } else {
                        acc.add_local(e, 0.0, local_extra);
                    }
                    sigma[a] = acc.frames.rotation[e].column(0) * (du * inv_h) + slope * du;
                    column[a] = Some(if j == e { 6 } else { 7 });
                }
            }
            if let Some(hs) = acc.ws_hessian.as_deref_mut() {
                add_kinetic_element_block(&mut hs[e], &mass.k, &xs, &sigma, &column, t.density, h);
                // the mass depends on Δc: ∂²/∂Δc∂q of rho/2 Σ K_ab(Δc) D_a.D_b is
                // Σ_b w_b . ∂D_b/∂q with w_b = rho Σ_a K'_ab D_a (K is linear in Δc, so
                // there is no ∂²/∂Δc² term)
                let mut rate = [Vector3::zeros(); 4];
                for (b, rate_b) in rate.iter_mut().enumerate() {
                    for a in 0..4 {
                        *rate_b += d[a] * (t.density * mass.dk_ddelta_c[a][b]);
                    }
                }
                add_mass_rate_coupling(&mut hs[e], &xs, &rate, &sigma, &column, inv_h);
            }
        }
        value
    }

    /// The kinetic residual D = (X - R(X̄, X^n))/h - R(X̄, V^n) of every rim vertex and
    /// its slope -(R_X'/h + R_V') along the rim's material coordinate u (the local,
    /// sliding derivative), bottom and top rim.
    fn kinetic_residuals(
        &self,
        frames: &Frames,
        c: &[f64],
        [res_b, res_t]: [&mut Vec<Vector3>; 2],
        [slope_b, slope_t]: [&mut Vec<Vector3>; 2],
    ) {
        let n = self.strip.segments;
        let inv_h = 1.0 / self.terms.h;
        let hist = self.history;
        res_b.resize(n + 1, Vector3::zeros());
        res_t.resize(n + 1, Vector3::zeros());
        slope_b.resize(n + 1, Vector3::zeros());
        slope_t.resize(n + 1, Vector3::zeros());
        for j in 0..=n {
            for top in [false, true] {
                let m = if top {
                    self.strip.material_top(j, c[j])
                } else {
                    self.strip.material_bottom(j, c[j])
                };
                let (us, xs, vs) = if top {
                    (&hist.u_top, &hist.x_top, &hist.v_top)
                } else {
                    (&hist.u_bottom, &hist.x_bottom, &hist.v_bottom)
                };
                let (k, inv_span, offset) = rim_segment(us, m.x, j);
                let (rx, drx) = interpolate_on(xs, k, inv_span, offset);
                let (rv, drv) = interpolate_on(vs, k, inv_span, offset);
                let x = if top {
                    frames.rim_top[j]
                } else {
                    frames.rim_bottom[j]
                };
                let d = (x.coords - rx) * inv_h - rv;
                // dD/du at fixed world motion: -(R_X'/h + R_V')
                let s = -(drx * inv_h + drv);
                if top {
                    res_t[j] = d;
                    slope_t[j] = s;
                } else {
                    res_b[j] = d;
                    slope_b[j] = s;
                }
            }
        }
    }

    /// Lumped kinetic term: sum_i M_i/2 |(m_i - m_i^n)/h - ṁ_i^n|^2 on the centerline
    /// points m_i = (x_i + y_i)/2 (material station (l i/n, 0), independent of c).
    pub(super) fn kinetic_lumped(&self, acc: &mut Accumulator) -> f64 {
        let n = self.strip.segments;
        let t = self.terms;
        let h = t.h;
        let hist = self.history;
        let mut value = 0.0;
        for i in 0..=n {
            let e = i.min(n - 1);
            let mass = lumped_centerline_mass(t.density, self.strip.length, self.strip.width, n, i);
            let m = Point3::from(
                (acc.frames.rim_bottom[i].coords + acc.frames.rim_top[i].coords) * 0.5,
            );
            let m_prev = (hist.x_bottom[i] + hist.x_top[i]) * 0.5;
            let v_prev = (hist.v_bottom[i] + hist.v_top[i]) * 0.5;
            let d = (m.coords - m_prev) / h - v_prev;
            value += 0.5 * mass * d.norm_squared();
            let material = Point3::new(self.strip.crease_station(i), 0.0, 0.0);
            acc.add_point_gradient(e, &material, &m, &(d * (mass / h)), None);
            if let Some(hs) = acc.ws_hessian.as_deref_mut() {
                let j = point_jacobian(&m) / h;
                hs[e] += j.transpose() * j * mass;
            }
        }
        value
    }
}

/// Adds to `block` the coupling of an element's mass rate with its motion, over
/// [twist; c_e; c_{e+1}]: a term Σ_b w_b(q) . ∂y_b/∂q_{Δc} whose
/// w_b = ∂²(...)/∂Δc∂y_b at vertex b gives the row
/// r = Σ_b [x_b × w_b; w_b] `scale` + w_b . σ_b (sliding column of b), and the
/// symmetric block e r^T + r e^T with e = ∂Δc/∂(c_e, c_{e+1}) = (-1, +1). `scale` is
/// ∂y/∂x (1/h for the kinetic residual, 1 for a position); `sigma` is ∂y_b/∂c_j.
pub(super) fn add_mass_rate_coupling(
    block: &mut Mat8,
    xs: &[Vector3; 4],
    rate: &[Vector3; 4],
    sigma: &[Vector3; 4],
    column: &[Option<usize>; 4],
    scale: f64,
) {
    let mut r = super::Vec8::zeros();
    for b in 0..4 {
        let moment = xs[b].cross(&rate[b]) * scale;
        for i in 0..3 {
            r[i] += moment[i];
            r[3 + i] += rate[b][i] * scale;
        }
        if let Some(cb) = column[b] {
            r[cb] += rate[b].dot(&sigma[b]);
        }
    }
    // e r^T + r e^T with e = (0, .., 0, -1, 1): only rows and columns 6 and 7 change
    for i in 0..8 {
        block[(6, i)] -= r[i];
        block[(7, i)] += r[i];
        block[(i, 6)] -= r[i];
        block[(i, 7)] += r[i];
    }
}

/// Adds to `block` the Gauss-Newton block of one element's kinetic term over
/// [twist; c_e; c_{e+1}]:
/// G = rho Σ_ab K_ab J_a^T J_b with J_a = [-[x_a]×/h, I/h | σ_a] for its vertices at
/// world positions `xs` (m), sliding columns `sigma` (local column `column`, 6 or 7,
/// for vertices on a free crease), mass pattern `k` (element mass / rho, m^2).
fn add_kinetic_element_block(
    block: &mut Mat8,
    k: &[[f64; 4]; 4],
    xs: &[Vector3; 4],
    sigma: &[Vector3; 4],
    column: &[Option<usize>; 4],
    rho: f64,
    h: f64,
) {
    // The twist block in closed form (rigid-body inertia structure): with
    // y_a = Σ_b K_ab x_b, row sums r_a and z = Σ r_a x_a, it is
    // [[Σ (x_a.y_a) I - y_a x_a^T, [z]×], [-[z]×, (Σ K) I]] / h^2.
    let mut rot = Matrix3::zeros();
    let mut z = Vector3::zeros();
    let mut total = 0.0;
    let mut y = [Vector3::zeros(); 4];
    for a in 0..4 {
        let mut r = 0.0;
        for b in 0..4 {
            y[a] += xs[b] * k[a][b];
            r += k[a][b];
        }
        rot += Matrix3::identity() * xs[a].dot(&y[a]) - y[a] * xs[a].transpose();
        z += xs[a] * r;
        total += r;
    }
    let inv_h2 = rho / (h * h);
    let rho_h = rho / h;
    let z_cross = skew(&z) * inv_h2;
    for j in 0..3 {
        for i in 0..3 {
            block[(i, j)] += rot[(i, j)] * inv_h2;
            block[(i, 3 + j)] += z_cross[(i, j)];
            block[(3 + i, j)] -= z_cross[(i, j)];
        }
        block[(3 + j, 3 + j)] += total * inv_h2;
    }
    for b in 0..4 {
        let Some(cb) = column[b] else { continue };
        // twist-local: (rho/h) Σ_a K_ab [x_a × σ_b; σ_b]
        let mut ang = Vector3::zeros();
        let mut r = 0.0;
        for a in 0..4 {
            ang += xs[a].cross(&sigma[b]) * k[a][b];
            r += k[a][b];
        }
        let lin = sigma[b] * r;
        for i in 0..3 {
            block[(i, cb)] += ang[i] * rho_h;
            block[(cb, i)] += ang[i] * rho_h;
            block[(3 + i, cb)] += lin[i] * rho_h;
            block[(cb, 3 + i)] += lin[i] * rho_h;
        }
        for a in 0..4 {
            if let Some(ca) = column[a] {
                block[(ca, cb)] += rho * k[a][b] * sigma[a].dot(&sigma[b]);
            }
        }
    }
}
