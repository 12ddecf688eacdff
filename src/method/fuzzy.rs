//! Fuzzy sets of the position hypotheses (section 4.1, Fig. 5): membership functions,
//! the rule (intersection = min) and defuzzification by first of maximum.

use serde::Deserialize;

/// A "low" membership: 1 at or below `full`, falling linearly to 0 at `zero` (Fig. 5a, 5b).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(from = "[f64; 2]")]
pub struct Low {
    /// Value up to which the membership is 1.
    pub full: f64,
    /// Value from which the membership is 0.
    pub zero: f64,
}

impl From<[f64; 2]> for Low {
    fn from(v: [f64; 2]) -> Self {
        Low {
            full: v[0],
            zero: v[1],
        }
    }
}

impl Low {
    /// Degree of membership of `x`, in [0, 1].
    pub fn membership(&self, x: f64) -> f64 {
        if x <= self.full {
            1.0
        } else if x >= self.zero {
            0.0
        } else {
            (self.zero - x) / (self.zero - self.full)
        }
    }
}

/// A trapezoid membership: 0 below `a`, rising to 1 at `b`, 1 up to `c`, 0 from `d` (Fig. 5c).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(from = "[f64; 4]")]
pub struct Trapezoid {
    /// Where the membership starts rising.
    pub a: f64,
    /// Where it reaches 1.
    pub b: f64,
    /// Where it starts falling.
    pub c: f64,
    /// Where it reaches 0.
    pub d: f64,
}

impl From<[f64; 4]> for Trapezoid {
    fn from(v: [f64; 4]) -> Self {
        Trapezoid {
            a: v[0],
            b: v[1],
            c: v[2],
            d: v[3],
        }
    }
}

impl Trapezoid {
    /// Degree of membership of `x`, in [0, 1].
    pub fn membership(&self, x: f64) -> f64 {
        if x <= self.a || x >= self.d {
            0.0
        } else if x < self.b {
            (x - self.a) / (self.b - self.a)
        } else if x <= self.c {
            1.0
        } else {
            (self.d - x) / (self.d - self.c)
        }
    }

    /// The same trapezoid with every breakpoint multiplied by `k` (fractions of H to metres).
    pub fn scaled(&self, k: f64) -> Trapezoid {
        Trapezoid {
            a: self.a * k,
            b: self.b * k,
            c: self.c * k,
            d: self.d * k,
        }
    }
}

/// The availability output (Fig. 5d) on [0, 1]: "available" rises linearly from `rise[0]`
/// to 1 at `rise[1]`; "not available" is its complement.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(from = "[f64; 2]")]
pub struct Availability {
    /// Start and end of the rise of "available".
    pub rise: [f64; 2],
}

impl From<[f64; 2]> for Availability {
    fn from(rise: [f64; 2]) -> Self {
        Availability { rise }
    }
}

/// The defuzzified answer for one position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Verdict {
    /// Whether "available" won over "not available".
    pub available: bool,
    /// The crisp availability by first of maximum on "available" (the arrow length of Fig. 4c).
    pub value: f64,
}

impl Availability {
    /// Defuzzifies a rule strength `mu` (the degree of "valid hypothesis").
    ///
    /// "available" is clipped at `mu` and "not available" at `1 - mu`; each set's
    /// first-of-maximum abscissa is its crisp value, and the set whose maximum is the
    /// higher wins (ties go to "not available").
    pub fn defuzzify(&self, mu: f64) -> Verdict {
        let [r0, r1] = self.rise;
        // First x where min(available(x), mu) == mu.
        let value = r0 + mu.clamp(0.0, 1.0) * (r1 - r0);
        Verdict {
            available: mu > 1.0 - mu,
            value,
        }
    }
}

/// The rule of section 4.1: IF roughness is low AND discontinuity is low AND height is
/// comfortable THEN valid; AND is the intersection (minimum).
pub fn rule(discontinuity_low: f64, roughness_low: f64, height_comfortable: f64) -> f64 {
    discontinuity_low.min(roughness_low).min(height_comfortable)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn low_at_breakpoints() {
        let l = Low {
            full: 0.1,
            zero: 0.3,
        };
        assert_eq!(l.membership(0.0), 1.0);
        assert_eq!(l.membership(0.1), 1.0);
        assert!((l.membership(0.2) - 0.5).abs() < 1e-12);
        assert_eq!(l.membership(0.3), 0.0);
        assert_eq!(l.membership(1.0), 0.0);
    }

    #[test]
    fn trapezoid_at_breakpoints() {
        let t = Trapezoid {
            a: 0.2,
            b: 0.4,
            c: 0.5,
            d: 0.7,
        };
        assert_eq!(t.membership(0.2), 0.0);
        assert!((t.membership(0.3) - 0.5).abs() < 1e-12);
        assert_eq!(t.membership(0.45), 1.0);
        assert!((t.membership(0.65) - 0.25).abs() < 1e-12);
        assert_eq!(t.membership(0.7), 0.0);
        assert_eq!(t.scaled(2.0).b, 0.8);
    }

    #[test]
    fn rule_is_the_minimum_and_defuzzifies_by_first_of_maximum() {
        assert_eq!(rule(0.9, 0.6, 0.8), 0.6);
        let a = Availability { rise: [0.2, 0.6] };
        let v = a.defuzzify(0.75);
        assert!(v.available);
        assert!((v.value - 0.5).abs() < 1e-12);
        let v = a.defuzzify(0.5);
        assert!(!v.available, "a tie is not available");
        assert!(!a.defuzzify(0.2).available);
    }
}
