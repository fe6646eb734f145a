//! Overlap ranges on the command line: `start:stop:step` (inclusive of stop), a list `a,b,c`, or one value.

use super::StudyError;

/// Parses `start:stop:step` (stop included, within a hundredth of a step), `a,b,c` or a single number.
/// Every value must lie in [0, 1); the result is never empty.
pub fn parse_range(s: &str) -> Result<Vec<f64>, StudyError> {
    let bad = |m: String| StudyError::Invalid(format!("overlap range `{s}`: {m}"));
    let num = |t: &str| t.trim().parse::<f64>().map_err(|_| bad(format!("`{}` is not a number", t.trim())));
    let values = if s.contains(':') {
        let parts: Vec<&str> = s.split(':').collect();
        if parts.len() != 3 {
            return Err(bad("expected start:stop:step".into()));
        }
        let (start, stop, step) = (num(parts[0])?, num(parts[1])?, num(parts[2])?);
        if !(step > 0.0 && step.is_finite()) {
            return Err(bad(format!("step must be positive, got {step}")));
        }
        if stop < start {
            return Err(bad(format!("empty: stop {stop} is below start {start}")));
        }
        let n = ((stop - start) / step + 0.01).floor() as usize + 1;
        if n > 10_000 {
            return Err(bad(format!("{n} values; at most 10000")));
        }
        // Rounded to 1e-9 so 0.05 + 13 * 0.05 prints as 0.7, not 0.7000000000000001.
        (0..n).map(|i| ((start + i as f64 * step) * 1e9).round() / 1e9).collect()
    } else {
        s.split(',').map(num).collect::<Result<Vec<_>, _>>()?
    };
    if values.is_empty() {
        return Err(bad("empty".into()));
    }
    if let Some(v) = values.iter().find(|v| !(**v >= 0.0 && **v < 1.0)) {
        return Err(bad(format!("overlap {v} outside [0, 1)")));
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_include_their_stop() {
        let v = parse_range("0.05:0.7:0.05").unwrap();
        assert_eq!(v.len(), 14);
        assert_eq!(v[0], 0.05);
        assert_eq!(v[13], 0.7);
        assert_eq!(parse_range("0.1:0.3:0.1").unwrap(), vec![0.1, 0.2, 0.3]);
        assert_eq!(parse_range("0.2:0.2:0.1").unwrap(), vec![0.2]);
    }

    #[test]
    fn lists_and_single_values() {
        assert_eq!(parse_range("0.1, 0.4,0.6").unwrap(), vec![0.1, 0.4, 0.6]);
        assert_eq!(parse_range("0.3").unwrap(), vec![0.3]);
    }

    #[test]
    fn bad_ranges_are_refused() {
        for s in ["0.5:0.2:0.1", "0.1:0.5:0", "0.1:0.5:-0.1", "0.1:0.5", "a:b:c", "", "1.2", "0.1,x", "-0.1"] {
            let e = parse_range(s).unwrap_err().to_string();
            assert!(e.contains("overlap range"), "{s}: {e}");
        }
        assert!(parse_range("0.5:0.2:0.1").unwrap_err().to_string().contains("empty"));
    }
}
