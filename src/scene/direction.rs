//! A direction given by the user (a pulley's swivel axis, a tilt axis) as a unit vector.

use nalgebra::Vector3;

/// `v / |v|`, or `None` when `v` has no direction (zero, or a component not finite). Where
/// `|v|` would overflow or lose digits to underflow (outside 1e-150 .. 1e150), `v` is
/// scaled by its largest component first: [1e308, 1e308, 1e308] is the direction
/// (1, 1, 1)/√3 (its `|v|` is infinite), [5e-324, 0, 0] is x. In that range `v / |v|`
/// exactly as before.
pub fn unit_direction(v: &Vector3<f64>) -> Option<Vector3<f64>> {
    if !v.iter().all(|x| x.is_finite()) {
        return None;
    }
    let n = v.norm();
    if n > 1e-150 && n < 1e150 {
        return Some(v / n);
    }
    let m = v.amax();
    if m == 0.0 {
        return None;
    }
    let s = v / m;
    Some(s / s.norm())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_of_any_scale() {
        let k = 1.0 / 3f64.sqrt();
        let d = unit_direction(&Vector3::new(1e308, 1e308, 1e308)).unwrap();
        assert!((d - Vector3::new(k, k, k)).norm() < 1e-15, "{d}");
        let d = unit_direction(&Vector3::new(-1e308, 1e308, 0.0)).unwrap();
        assert!((d - Vector3::new(-1.0, 1.0, 0.0) / 2f64.sqrt()).norm() < 1e-15);
        assert_eq!(
            unit_direction(&Vector3::new(5e-324, 0.0, 0.0)),
            Some(Vector3::x())
        );
        assert_eq!(
            unit_direction(&Vector3::new(0.0, 3.0, 4.0)),
            Some(Vector3::new(0.0, 0.6, 0.8))
        );
        assert_eq!(unit_direction(&Vector3::zeros()), None);
        assert_eq!(unit_direction(&Vector3::new(f64::NAN, 1.0, 0.0)), None);
        assert_eq!(unit_direction(&Vector3::new(f64::INFINITY, 1.0, 0.0)), None);
    }
}
