//! The report's axes: the range a plot shows, its ticks (every decade of a log axis,
//! 1-2-5 steps of a linear one) and their labels in engineering units (`0.1 ms`,
//! `1 ms`, `10 ms`; `0.1 mm`; `10 µm`). Pure: numbers in, numbers and strings out.

/// The unit an axis is labelled in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    /// s: run times, time steps, simulated time.
    Second,
    /// m: errors, distances.
    Metre,
    /// J: energies.
    Joule,
    /// Dimensionless counts (elements n): plain numbers.
    Count,
}

impl Unit {
    fn symbol(self) -> &'static str {
        match self {
            Unit::Second => "s",
            Unit::Metre => "m",
            Unit::Joule => "J",
            Unit::Count => "",
        }
    }

    /// The largest SI prefix used, as a power of 1000: seconds and metres stay in s and
    /// m (a run of 100 s, not 0.1 ks), energies may reach kJ.
    fn max_prefix(self) -> i32 {
        match self {
            Unit::Joule => 1,
            _ => 0,
        }
    }
}

const PREFIXES: [(i32, &str); 6] = [
    (-4, "p"),
    (-3, "n"),
    (-2, "µ"),
    (-1, "m"),
    (0, ""),
    (1, "k"),
];

/// `v` with up to 3 significant digits, no trailing zeros (`0.1`, `2.5`, `100`).
fn short(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let digits = (2 - v.abs().log10().floor() as i32).clamp(0, 12) as usize;
    let s = format!("{v:.digits$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

/// `v` in engineering units: below the base unit the prefix 1000^k with k =
/// round(log10 |v| / 3), so the number is 0.1 to 100 (`0.1 ms`, `1 ms`, `10 ms`,
/// `0.1 s`); from the base unit up k = floor(log10 |v| / 3) (`100 J`, `1.5 kJ`), within
/// the prefixes the unit allows; counts are plain numbers.
pub fn engineering(v: f64, unit: Unit) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    if unit == Unit::Count {
        return short(v);
    }
    if v == 0.0 {
        return format!("0 {}", unit.symbol());
    }
    // the decade, robust to 1e-3 being 0.000999... in binary
    let e = (v.abs().log10() + 1e-9).floor() as i32;
    let k = if e >= 0 {
        e.div_euclid(3)
    } else {
        ((e as f64) / 3.0).round() as i32
    }
    .clamp(PREFIXES[0].0, unit.max_prefix());
    let prefix = PREFIXES.iter().find(|p| p.0 == k).map_or("", |p| p.1);
    format!("{} {prefix}{}", short(v / 10f64.powi(3 * k)), unit.symbol())
}

/// How an axis maps values: log10 or as they are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    Log,
    Linear,
}

/// An axis's shown range and ticks, in plot coordinates (log10 of the value on a log
/// axis, the value on a linear one).
#[derive(Clone, Debug, PartialEq)]
pub struct Ticks {
    pub scale: Scale,
    /// The shown range, plot coordinates.
    pub range: (f64, f64),
    /// Labelled ticks, plot coordinates: every decade in the range (log), every
    /// 1-2-5 step (linear).
    pub major: Vec<f64>,
    /// Unlabelled grid lines: 2..9 times each decade (log), half steps (linear).
    pub minor: Vec<f64>,
}

impl Ticks {
    /// The value at plot coordinate `p`.
    pub fn value(&self, p: f64) -> f64 {
        match self.scale {
            Scale::Log => 10f64.powf(p),
            Scale::Linear => p,
        }
    }

    /// The plot coordinate of value `v` (None for v <= 0 on a log axis).
    pub fn coord(&self, v: f64) -> Option<f64> {
        match self.scale {
            Scale::Log => (v > 0.0 && v.is_finite()).then(|| v.log10()),
            Scale::Linear => v.is_finite().then_some(v),
        }
    }

    /// Keep every `k`-th labelled tick (1: all), counted from the one nearest a
    /// multiple of `k` decades or steps so thinned axes label round values.
    pub fn thinned(&self, k: usize) -> Vec<f64> {
        if k <= 1 {
            return self.major.clone();
        }
        let step = match self.major.as_slice() {
            [a, b, ..] => b - a,
            _ => return self.major.clone(),
        };
        self.major
            .iter()
            .copied()
            .filter(|p| ((p / step).round() as i64).rem_euclid(k as i64) == 0)
            .collect()
    }
}

/// A log axis over the positive finite `values`, widened by a factor 1.5 on each side,
/// then to whole decades on the nearer side until at least two decades lie inside, so
/// every axis has at least two labelled decades. None without a positive finite value.
pub fn log_ticks(values: impl IntoIterator<Item = f64>) -> Option<Ticks> {
    let (lo, hi) = values
        .into_iter()
        .filter(|v| *v > 0.0 && v.is_finite())
        .fold(None, |r: Option<(f64, f64)>, v| {
            Some(r.map_or((v, v), |(a, b)| (a.min(v), b.max(v))))
        })?;
    let (mut a, mut b) = ((lo / 1.5).log10(), (hi * 1.5).log10());
    let decades = |a: f64, b: f64| (b + 1e-9).floor() as i64 - (a - 1e-9).ceil() as i64 + 1;
    // a decade reached by widening sits 0.06 decade inside the edge, so its label is
    // not in the corner where the other axis's last label is
    while decades(a, b) < 2 {
        let (fa, cb) = ((a + 1e-9).floor(), (b - 1e-9).ceil());
        if a - fa <= cb - b {
            a = fa - 0.06;
        } else {
            b = cb + 0.06;
        }
    }
    let first = (a - 1e-9).ceil() as i64;
    let last = (b + 1e-9).floor() as i64;
    let major: Vec<f64> = (first..=last).map(|e| e as f64).collect();
    let minor = ((a.floor() as i64)..=(b.ceil() as i64))
        .flat_map(|e| (2..10).map(move |m| e as f64 + (m as f64).log10()))
        .filter(|p| *p >= a && *p <= b)
        .collect();
    Some(Ticks {
        scale: Scale::Log,
        range: (a, b),
        major,
        minor,
    })
}

/// A linear axis over the finite `values` (and 0 when `with_zero`): a 1, 2 or 5 times
/// 10^k step giving 4 to 10 labelled ticks, the range widened to whole steps. None
/// without a finite value.
pub fn linear_ticks(values: impl IntoIterator<Item = f64>, with_zero: bool) -> Option<Ticks> {
    let (mut lo, mut hi) = values
        .into_iter()
        .filter(|v| v.is_finite())
        .fold(None, |r: Option<(f64, f64)>, v| {
            Some(r.map_or((v, v), |(a, b)| (a.min(v), b.max(v))))
        })?;
    if with_zero {
        lo = lo.min(0.0);
        hi = hi.max(0.0);
    }
    if hi - lo <= f64::EPSILON * hi.abs().max(lo.abs()).max(1e-300) {
        let pad = if hi == 0.0 { 1.0 } else { 0.1 * hi.abs() };
        (lo, hi) = (lo - pad, hi + pad);
    }
    let raw = (hi - lo) / 5.0;
    let base = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * base)
        .find(|s| (hi - lo) / s <= 8.0)
        .unwrap_or(10.0 * base);
    // a value a rounding error past a step (1.0000000002 s) does not add a step
    let (first, last) = (
        (lo / step + 1e-9).floor() as i64,
        (hi / step - 1e-9).ceil() as i64,
    );
    let major: Vec<f64> = (first..=last).map(|k| k as f64 * step).collect();
    let minor = (2 * first..=2 * last)
        .filter(|k| k % 2 != 0)
        .map(|k| k as f64 * 0.5 * step)
        .collect();
    Some(Ticks {
        scale: Scale::Linear,
        range: (first as f64 * step, last as f64 * step),
        major,
        minor,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decades_read_in_engineering_units() {
        let s = |v| engineering(v, Unit::Second);
        assert_eq!(
            [1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0].map(s),
            ["0.1 ms", "1 ms", "10 ms", "0.1 s", "1 s", "10 s", "100 s"]
        );
        let m = |v| engineering(v, Unit::Metre);
        assert_eq!(
            [1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2].map(m),
            ["0.1 µm", "1 µm", "10 µm", "0.1 mm", "1 mm", "10 mm"]
        );
        assert_eq!(engineering(2.5e-4, Unit::Second), "0.25 ms");
        assert_eq!(engineering(1500.0, Unit::Joule), "1.5 kJ");
        assert_eq!(engineering(100.0, Unit::Joule), "100 J");
        assert_eq!(engineering(-0.02, Unit::Joule), "-20 mJ");
        assert_eq!(engineering(0.0, Unit::Joule), "0 J");
        assert_eq!(engineering(100.0, Unit::Count), "100");
        assert_eq!(engineering(1e-15, Unit::Metre), "0.001 pm");
    }

    #[test]
    fn a_log_axis_labels_every_decade_and_at_least_two() {
        // 1.1e-3 .. 1.3e-3: widened to 7.3e-4 .. 1.95e-3, then to the nearer decade
        let t = log_ticks([1.1e-3, 1.3e-3]).unwrap();
        assert_eq!(t.major.len(), 2, "{t:?}");
        assert!(t.major.iter().all(|p| p.fract() == 0.0));
        // 2e-5 .. 3e-2: every decade inside, and only those
        let t = log_ticks([2e-5, 3e-2, -1.0, f64::NAN]).unwrap();
        assert_eq!(t.major, vec![-4.0, -3.0, -2.0]);
        assert!(t.range.0 <= (2e-5f64 / 1.5).log10() + 1e-12);
        assert!(t.minor.iter().all(|p| *p >= t.range.0 && *p <= t.range.1));
        assert_eq!(log_ticks([0.0, -2.0]), None);
        assert_eq!(t.value(-3.0), 1e-3);
        assert_eq!(t.thinned(2), vec![-4.0, -2.0]);
        assert_eq!(t.thinned(3), vec![-3.0]);
    }

    #[test]
    fn a_linear_axis_steps_by_one_two_or_five() {
        let t = linear_ticks([-0.013, 0.041], true).unwrap();
        assert_eq!(t.major.len(), 8, "{t:?}");
        let step = t.major[1] - t.major[0];
        assert!((step - 0.01).abs() < 1e-15, "{t:?}");
        assert!(t.range.0 <= -0.013 && t.range.1 >= 0.041);
        let t = linear_ticks([0.0, 1.0 + 1e-12], true).unwrap();
        assert_eq!(t.range, (0.0, 1.0), "{t:?}");
        let flat = linear_ticks([0.0, 0.0], false).unwrap();
        assert!(flat.range.1 > flat.range.0);
        assert!(linear_ticks([f64::NAN], false).is_none());
    }
}
