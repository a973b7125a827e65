//! Units of logged signals and their exact conversion to SI.
//!
//! Every conversion is a multiplication by an exact factor (international foot
//! 0.3048 m, standard gravity 9.80665 m/s², 1 rev = 2π rad, 1 lbf = 4.4482216152605 N);
//! eRPM is divided by the motor's pole-pair count.

use std::f64::consts::PI;

use crate::vehicle::STANDARD_GRAVITY;

/// Physical dimension of a signal, to refuse e.g. `m/s` for body rates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dimension {
    /// Time, SI unit s.
    Time,
    /// Speed, SI unit m/s.
    Speed,
    /// Angular rate (body rates, rotor speeds), SI unit rad/s.
    AngularRate,
    /// Angular acceleration, SI unit rad/s².
    AngularAcceleration,
    /// Linear acceleration / specific force, SI unit m/s².
    Acceleration,
    /// Force, SI unit N.
    Force,
    /// Moment, SI unit N m.
    Moment,
    /// Length, SI unit m.
    Length,
    /// Dimensionless (quaternion components), unit "1".
    Dimensionless,
}

impl Dimension {
    /// Name of the SI unit.
    pub fn si_unit(self) -> &'static str {
        match self {
            Self::Time => "s",
            Self::Speed => "m/s",
            Self::AngularRate => "rad/s",
            Self::AngularAcceleration => "rad/s^2",
            Self::Acceleration => "m/s^2",
            Self::Force => "N",
            Self::Moment => "N m",
            Self::Length => "m",
            Self::Dimensionless => "1",
        }
    }
}

/// International foot, m (exact).
pub const FOOT: f64 = 0.3048;
/// Pound-force, N (exact by definition from lb and g_n).
pub const POUND_FORCE: f64 = 4.448_221_615_260_5;

/// A unit: its dimension and the factor that converts a value to SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unit {
    /// Dimension.
    pub dimension: Dimension,
    /// SI value of one unit.
    pub to_si: f64,
}

/// Why a unit name was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum UnitError {
    /// Not a unit the crate knows.
    #[error(
        "unknown unit {name:?} (known: s ms us ns, m/s ft/s km/h kn, rad/s deg/s rpm \
         rev/s erpm, rad/s^2 deg/s^2 rpm/s, m/s^2 g ft/s^2, N lbf, N m, lbf ft, m ft, 1)"
    )]
    Unknown {
        /// The name as given.
        name: String,
    },
    /// `erpm` without the motor's pole pairs.
    #[error("unit \"erpm\" needs `pole_pairs` (motor pole pairs)")]
    PolePairsMissing,
    /// Pole pairs that are not a whole number ≥ 1.
    #[error("`pole_pairs` = {pole_pairs} must be a whole number >= 1")]
    BadPolePairs {
        /// The value given.
        pole_pairs: f64,
    },
    /// A unit of another dimension than the signal's.
    #[error(
        "unit {name:?} is a {found:?} unit, but {what} needs a {want:?} unit such as {:?}",
        want.si_unit()
    )]
    WrongDimension {
        /// The name as given.
        name: String,
        /// Its dimension.
        found: Dimension,
        /// The signal's dimension.
        want: Dimension,
        /// The signal (its mapping key, e.g. `rates`).
        what: &'static str,
    },
}

/// Parses a unit name. `pole_pairs` is required for `erpm` (electrical RPM) and
/// ignored otherwise. Names are case-insensitive; `^2` and `2` are accepted in
/// accelerations (`rad/s^2`, `rad/s2`).
pub fn parse_unit(name: &str, pole_pairs: Option<f64>) -> Result<Unit, UnitError> {
    use Dimension::*;
    let n = name
        .trim()
        .to_ascii_lowercase()
        .replace("^2", "2")
        .replace('²', "2");
    let rpm = 2.0 * PI / 60.0;
    let (dimension, to_si) = match n.as_str() {
        "s" => (Time, 1.0),
        "ms" => (Time, 1e-3),
        "us" | "µs" => (Time, 1e-6),
        "ns" => (Time, 1e-9),
        "m/s" => (Speed, 1.0),
        "ft/s" => (Speed, FOOT),
        "km/h" => (Speed, 1.0 / 3.6),
        "kn" | "kt" => (Speed, 1852.0 / 3600.0),
        "rad/s" => (AngularRate, 1.0),
        "deg/s" => (AngularRate, PI / 180.0),
        "rpm" => (AngularRate, rpm),
        "rev/s" | "hz" => (AngularRate, 2.0 * PI),
        "erpm" => {
            let pp = pole_pairs.ok_or(UnitError::PolePairsMissing)?;
            if !(pp.is_finite() && pp >= 1.0 && pp.fract() == 0.0) {
                return Err(UnitError::BadPolePairs { pole_pairs: pp });
            }
            (AngularRate, rpm / pp)
        }
        "rad/s2" => (AngularAcceleration, 1.0),
        "deg/s2" => (AngularAcceleration, PI / 180.0),
        "rpm/s" => (AngularAcceleration, rpm),
        "m/s2" => (Acceleration, 1.0),
        "g" => (Acceleration, STANDARD_GRAVITY),
        "ft/s2" => (Acceleration, FOOT),
        "n" => (Force, 1.0),
        "lbf" => (Force, POUND_FORCE),
        "n m" | "nm" | "n*m" | "n.m" => (Moment, 1.0),
        "lbf ft" | "ft lbf" => (Moment, POUND_FORCE * FOOT),
        "m" => (Length, 1.0),
        "ft" => (Length, FOOT),
        "1" | "" => (Dimensionless, 1.0),
        _ => {
            return Err(UnitError::Unknown {
                name: name.to_string(),
            });
        }
    };
    Ok(Unit { dimension, to_si })
}

/// Parses `name` and checks it has dimension `want`; `what` names the signal in errors.
pub fn unit_for(
    name: &str,
    pole_pairs: Option<f64>,
    want: Dimension,
    what: &'static str,
) -> Result<Unit, UnitError> {
    let unit = parse_unit(name, pole_pairs)?;
    if unit.dimension == want {
        Ok(unit)
    } else {
        Err(UnitError::WrongDimension {
            name: name.to_string(),
            found: unit.dimension,
            want,
            what,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_are_exact_factors() {
        // Exact by definition: compared with ==, no tolerance.
        assert_eq!(parse_unit("ft/s", None).unwrap().to_si, 0.3048);
        assert_eq!(parse_unit("g", None).unwrap().to_si, 9.80665);
        assert_eq!(parse_unit("deg/s", None).unwrap().to_si, PI / 180.0);
        assert_eq!(parse_unit("RPM", None).unwrap().to_si, PI / 30.0);
        // 7 pole pairs: 7000 eRPM = 1000 RPM = 104.719… rad/s (1 ulp tolerance).
        let e = parse_unit("eRPM", Some(7.0)).unwrap();
        assert!((7000.0 * e.to_si - 1000.0 * PI / 30.0).abs() <= 2.0 * f64::EPSILON * 105.0);
        assert_eq!(
            parse_unit("rad/s²", None).unwrap().dimension,
            Dimension::AngularAcceleration
        );
    }

    #[test]
    fn wrong_dimension_and_unknown_units_are_refused() {
        let e = unit_for("m/s", None, Dimension::AngularRate, "rates").unwrap_err();
        assert_eq!(
            e,
            UnitError::WrongDimension {
                name: "m/s".into(),
                found: Dimension::Speed,
                want: Dimension::AngularRate,
                what: "rates"
            }
        );
        assert!(
            e.to_string().contains("rates needs a AngularRate unit"),
            "{e}"
        );
        let e = parse_unit("furlong/fortnight", None).unwrap_err();
        assert!(e.to_string().starts_with("unknown unit"), "{e}");
        assert_eq!(parse_unit("erpm", None), Err(UnitError::PolePairsMissing));
        assert_eq!(
            parse_unit("erpm", Some(6.5)),
            Err(UnitError::BadPolePairs { pole_pairs: 6.5 })
        );
    }
}
