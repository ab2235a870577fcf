//! Numbers in tables and reports: one function per precision rule, named after it.
//!
//! | function | rule | used by |
//! | --- | --- | --- |
//! | [`sig6`] | 6 significant digits, scientific outside [1e-3, 1e6) | the analysis table |
//! | [`sig4`], [`signed_sig4`] | ≤ 4 significant digits, trailing zeros dropped, scientific outside [1e-4, 1e6) | reproduction tables |
//! | [`dec4`] | 4 decimals in [1e-3, 1e4), else 4 significant digits in scientific | cross-code tables |
//! | [`sci3`] | 4 significant digits, always scientific | bench tables |
//! | [`sci4_or_blank`] | 5 significant digits, always scientific; empty for none | accuracy CSV |
//! | [`sig3_or_dash`] | 3 significant digits, scientific outside [1e-3, 1e4); `—` for none | accuracy tables |
//!
//! Numbers written into generated decks follow none of these: they must read back to the
//! same value ([`crate::xcode::decks::num`], shortest round-trip form).

/// 6 significant digits, scientific notation outside [1e-3, 1e6).
pub fn sig6(x: f64) -> String {
    if x == 0.0 {
        "0".to_string()
    } else if !x.is_finite() {
        format!("{x}")
    } else if (1e-3..1e6).contains(&x.abs()) {
        let digits = 5 - x.abs().log10().floor() as i32;
        format!("{:.*}", digits.max(0) as usize, x)
    } else {
        format!("{x:.5e}")
    }
}

/// At most 4 significant digits, without trailing zeros, scientific notation (4 digits)
/// outside [1e-4, 1e6).
pub fn sig4(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let mag = x.abs().log10().floor() as i32;
    if !(-4..6).contains(&mag) {
        return format!("{x:.3e}");
    }
    let decimals = (3 - mag).max(0) as usize;
    let s = format!("{x:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// [`sig4`] with a `+` on non-negative numbers.
pub fn signed_sig4(x: f64) -> String {
    if x >= 0.0 {
        format!("+{}", sig4(x))
    } else {
        sig4(x)
    }
}

/// 4 decimals in [1e-3, 1e4), else scientific notation with 4 significant digits.
pub fn dec4(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if x.abs() >= 1e-3 && x.abs() < 1e4 {
        format!("{x:.4}")
    } else {
        format!("{x:.3e}")
    }
}

/// Scientific notation with 4 significant digits.
pub fn sci3(x: f64) -> String {
    format!("{x:.3e}")
}

/// Scientific notation with 5 significant digits; empty for `None`.
pub fn sci4_or_blank(x: Option<f64>) -> String {
    x.map_or(String::new(), |x| format!("{x:.4e}"))
}

/// Three significant figures, scientific notation outside [1e-3, 1e4); `—` for `None`.
pub fn sig3_or_dash(x: Option<f64>) -> String {
    match x {
        None => "—".into(),
        Some(0.0) => "0".into(),
        Some(x) if !x.is_finite() || x.abs() < 1e-3 || x.abs() >= 1e4 => format!("{x:.2e}"),
        Some(x) => {
            let decimals = (2 - x.abs().log10().floor() as i32).max(0) as usize;
            format!("{x:.decimals$}")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers() {
        assert_eq!(sig6(0.0), "0");
        assert_eq!(sig6(0.637), "0.637000");
        assert_eq!(sig6(6.074), "6.07400");
        assert_eq!(sig6(4000.0), "4000.00");
        assert_eq!(sig6(1e-6), "1.00000e-6");
        assert_eq!(sig6(-0.5), "-0.500000");
    }

    #[test]
    fn significant_digits() {
        assert_eq!(sig4(0.5923), "0.5923");
        assert_eq!(sig4(6.074), "6.074");
        assert_eq!(sig4(0.0015), "0.0015");
        assert_eq!(sig4(12.36), "12.36");
        assert_eq!(sig4(2084.0), "2084");
        assert_eq!(sig4(1.15e-4), "0.000115");
        assert_eq!(sig4(3.0e-7), "3.000e-7");
        assert_eq!(signed_sig4(0.0015), "+0.0015");
    }

    #[test]
    fn the_other_rules() {
        assert_eq!(dec4(0.0), "0");
        assert_eq!(dec4(0.637), "0.6370");
        assert_eq!(dec4(12344.0), "1.234e4");
        assert_eq!(dec4(-2e-4), "-2.000e-4");
        assert_eq!(sci3(1234.4), "1.234e3");
        assert_eq!(sci3(0.0), "0.000e0");
        assert_eq!(sci4_or_blank(None), "");
        assert_eq!(sci4_or_blank(Some(0.637)), "6.3700e-1");
        assert_eq!(sig3_or_dash(None), "—");
        assert_eq!(sig3_or_dash(Some(0.0)), "0");
        assert_eq!(sig3_or_dash(Some(0.6374)), "0.637");
        assert_eq!(sig3_or_dash(Some(12.34)), "12.3");
        assert_eq!(sig3_or_dash(Some(1234.0)), "1234");
        assert_eq!(sig3_or_dash(Some(5e-4)), "5.00e-4");
    }
}
