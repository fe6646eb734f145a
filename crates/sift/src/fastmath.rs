//! Approximations used by OpenCV's SIFT (`cv::fastAtan2`), written branch-light so loops vectorise.

const P1: f32 = 0.999_787_87 * (180.0 / std::f32::consts::PI);
const P3: f32 = -0.325_808_4 * (180.0 / std::f32::consts::PI);
const P5: f32 = 0.155_578_65 * (180.0 / std::f32::consts::PI);
const P7: f32 = -0.044_326_556 * (180.0 / std::f32::consts::PI);

/// Angle of the vector (x, y) in degrees in [0, 360], OpenCV's `fastAtan2` polynomial (error < 0.01 deg).
#[inline(always)]
pub fn atan2_deg(y: f32, x: f32) -> f32 {
    let ax = x.abs();
    let ay = y.abs();
    let eps = f64::EPSILON as f32;
    let swap = ax < ay;
    let (num, den) = if swap { (ax, ay) } else { (ay, ax) };
    let c = num / (den + eps);
    let c2 = c * c;
    let p = (((P7 * c2 + P5) * c2 + P3) * c2 + P1) * c;
    let a = if swap { 90.0 - p } else { p };
    let a = if x < 0.0 { 180.0 - a } else { a };
    if y < 0.0 { 360.0 - a } else { a }
}

/// Round half to even, as OpenCV's `cvRound` under the default rounding mode.
#[inline(always)]
pub fn round_i32(v: f32) -> i32 {
    v.round_ties_even() as i32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atan2_is_close_to_std() {
        for i in 0..720 {
            let t = (i as f32) * 0.5f32.to_radians() + 0.001;
            let (y, x) = (t.sin() * 3.0, t.cos() * 3.0);
            let mut want = y.atan2(x).to_degrees();
            if want < 0.0 {
                want += 360.0;
            }
            let got = atan2_deg(y, x);
            let diff = (got - want).abs().min(360.0 - (got - want).abs());
            assert!(diff < 0.02, "{t}: {got} vs {want}");
        }
        assert_eq!(atan2_deg(0.0, 0.0), 0.0);
    }
}
