//! Numbers written into messages, one rule each.

/// An angle (rad) for a message: 4 decimals from 1 mrad up (as always written), else 3
/// significant digits in exponent form, so that a small error never reads "0.0000 rad".
pub(crate) fn angle_text(rad: f64) -> String {
    if rad == 0.0 || !rad.is_finite() || rad.abs() >= 1e-3 {
        format!("{rad:.4}")
    } else {
        format!("{rad:.2e}")
    }
}

#[cfg(test)]
mod tests {
    use super::angle_text;

    #[test]
    fn small_angles_keep_their_digits() {
        assert_eq!(angle_text(0.12345), "0.1235");
        assert_eq!(angle_text(-0.002), "-0.0020");
        assert_eq!(angle_text(3.2e-5), "3.20e-5");
        assert_eq!(angle_text(0.0), "0.0000");
    }
}
