//! Lists of values on the command line, as `parse_range` reads overlaps: `a,b,c`, `start:stop[:step]` (stop
//! included), or one value; never empty, no value twice.

use super::StudyError;

/// At most this many values in one list.
const MAX_VALUES: usize = 10_000;

/// Splits `start:stop` or `start:stop:step` into its parts; `None` for a list or a single value.
fn range_parts(s: &str) -> Option<Vec<&str>> {
    s.contains(':').then(|| s.split(':').map(str::trim).collect())
}

/// Refuses an empty list and a value given twice (`what` names the list, e.g. `--seeds 0,0`).
fn check_distinct<T: PartialEq + std::fmt::Display>(values: &[T], what: &str) -> Result<(), StudyError> {
    if values.is_empty() {
        return Err(StudyError::Invalid(format!("{what}: empty")));
    }
    for (i, v) in values.iter().enumerate() {
        if values[..i].contains(v) {
            return Err(StudyError::Invalid(format!("{what}: {v} given twice")));
        }
    }
    Ok(())
}

/// Whole numbers: `a,b,c`, `start:stop` (both included), `start:stop:step`, or one number. `flag` names the
/// list in errors (`--seeds`).
pub fn parse_whole_numbers(s: &str, flag: &str) -> Result<Vec<u64>, StudyError> {
    let what = format!("{flag} `{s}`");
    let bad = |m: String| StudyError::Invalid(format!("{what}: {m}"));
    let num = |t: &str| t.trim().parse::<u64>().map_err(|_| bad(format!("`{}` is not a whole number", t.trim())));
    let values = match range_parts(s) {
        Some(parts) => {
            let (start, stop, step) = match parts[..] {
                [a, b] => (num(a)?, num(b)?, 1),
                [a, b, c] => (num(a)?, num(b)?, num(c)?),
                _ => return Err(bad("expected start:stop or start:stop:step".into())),
            };
            if step == 0 {
                return Err(bad("step must be at least 1".into()));
            }
            if stop < start {
                return Err(bad(format!("empty: stop {stop} is below start {start}")));
            }
            // Counted before adding the first value, so that 0:18446744073709551615 cannot overflow.
            let gaps = (stop - start) / step;
            if gaps >= MAX_VALUES as u64 {
                return Err(bad(format!("{} values; at most {MAX_VALUES}", u128::from(gaps) + 1)));
            }
            let n = gaps + 1;
            (0..n).map(|i| start + i * step).collect()
        }
        None => s.split(',').map(num).collect::<Result<Vec<_>, _>>()?,
    };
    check_distinct(&values, &what)?;
    Ok(values)
}

/// Numbers at least 0: `a,b,c`, `start:stop:step` (stop included within a hundredth of a step), or one number.
/// `flag` names the list in errors (`--range`).
pub fn parse_numbers(s: &str, flag: &str) -> Result<Vec<f64>, StudyError> {
    let what = format!("{flag} `{s}`");
    let bad = |m: String| StudyError::Invalid(format!("{what}: {m}"));
    let num = |t: &str| {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| bad(format!("`{}` is not a number", t.trim())))
    };
    let values: Vec<f64> = match range_parts(s) {
        Some(parts) => {
            let [a, b, c] = parts[..] else {
                return Err(bad("expected start:stop:step".into()));
            };
            let (start, stop, step) = (num(a)?, num(b)?, num(c)?);
            if step <= 0.0 {
                return Err(bad(format!("step must be positive, got {step}")));
            }
            if stop < start {
                return Err(bad(format!("empty: stop {stop} is below start {start}")));
            }
            let n = ((stop - start) / step + 0.01).floor() as usize + 1;
            if n > MAX_VALUES {
                return Err(bad(format!("{n} values; at most {MAX_VALUES}")));
            }
            // Rounded to 1e-9 so 0.5 + 3 * 0.1 prints as 0.8, not 0.8000000000000002.
            (0..n).map(|i| ((start + i as f64 * step) * 1e9).round() / 1e9).collect()
        }
        None => s.split(',').map(num).collect::<Result<Vec<_>, _>>()?,
    };
    if let Some(v) = values.iter().find(|v| **v < 0.0) {
        return Err(bad(format!("{v} is negative")));
    }
    check_distinct(&values, &what)?;
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_numbers_in_lists_and_ranges() {
        assert_eq!(parse_whole_numbers("0:4", "--seeds").unwrap(), [0, 1, 2, 3, 4]);
        assert_eq!(parse_whole_numbers("1:7:3", "--seeds").unwrap(), [1, 4, 7]);
        assert_eq!(parse_whole_numbers("4, 1,2", "--robots").unwrap(), [4, 1, 2]);
        assert_eq!(parse_whole_numbers("3", "--robots").unwrap(), [3]);
        let e = |s: &str| parse_whole_numbers(s, "--seeds").unwrap_err().to_string();
        assert_eq!(e("0:x"), "--seeds `0:x`: `x` is not a whole number");
        assert_eq!(e("-1"), "--seeds `-1`: `-1` is not a whole number");
        assert_eq!(e("5:2"), "--seeds `5:2`: empty: stop 2 is below start 5");
        assert_eq!(e("1,2,1"), "--seeds `1,2,1`: 1 given twice");
        assert_eq!(e("0:4:0"), "--seeds `0:4:0`: step must be at least 1");
        assert_eq!(e("1:2:3:4"), "--seeds `1:2:3:4`: expected start:stop or start:stop:step");
        assert!(e("0:99999").contains("at most 10000"));
        assert!(e("0:18446744073709551615").contains("18446744073709551616 values; at most 10000"));
        assert!(e("5:18446744073709551615:2").contains("at most 10000"));
        assert!(e("").contains("is not a whole number"));
    }

    #[test]
    fn numbers_in_lists_and_ranges() {
        assert_eq!(parse_numbers("12", "--range").unwrap(), [12.0]);
        assert_eq!(parse_numbers("4,8.5", "--range").unwrap(), [4.0, 8.5]);
        assert_eq!(parse_numbers("0.5:0.8:0.1", "--range").unwrap(), [0.5, 0.6, 0.7, 0.8]);
        let e = |s: &str| parse_numbers(s, "--range").unwrap_err().to_string();
        assert_eq!(e("-3"), "--range `-3`: -3 is negative");
        assert_eq!(e("4,4"), "--range `4,4`: 4 given twice");
        assert_eq!(e("inf"), "--range `inf`: `inf` is not a number");
        assert_eq!(e("2:4"), "--range `2:4`: expected start:stop:step");
        assert_eq!(e("2:4:0"), "--range `2:4:0`: step must be positive, got 0");
    }
}
