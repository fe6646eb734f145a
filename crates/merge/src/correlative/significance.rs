//! The significance test: the best answer against the best clearly different one (Lowe's ratio test).

use mrslam_core::Pose2;

/// How far the best answer stands above the best clearly different one, both scored on the fine field (Lowe's
/// ratio test; Olson's ambiguity test for loop closures).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Significance {
    /// The best answer, `T_a_b`.
    pub best: Pose2,
    /// Its fine score.
    pub best_score: i64,
    /// The best answer more than [`crate::AnswerParams::rival_distinct_m`] away, among the global search's
    /// answers above its pruning floor; None when there was none.
    pub rival: Option<Pose2>,
    /// Its fine score (0 when there was none).
    pub rival_score: i64,
}

impl Significance {
    /// `(best - rival) / best`: the share by which the winner beats every clearly different pose searched (1 when
    /// none was left above the search's pruning floor, 0 when the best score is not positive).
    pub fn margin(&self) -> f64 {
        if self.best_score <= 0 {
            0.0
        } else if self.rival.is_none() {
            1.0
        } else {
            (self.best_score - self.rival_score.max(0)) as f64 / self.best_score as f64
        }
    }

    /// Why the answer is refused at `min_margin`, naming the rival; None when it stands out enough (or the
    /// test is off, `min_margin` ≤ 0).
    pub(super) fn refusal(&self, min_margin: f64) -> Option<String> {
        if min_margin <= 0.0 || self.margin() >= min_margin {
            return None;
        }
        let (x, y, deg) = (self.best.translation.x, self.best.translation.y, self.best.rotation.angle().to_degrees());
        if self.best_score <= 0 {
            return Some(format!(
                "no pose scores above 0 (b's walls fall on a's free space more than on its walls): the best (x {x:.2} \
                 m, y {y:.2} m, {deg:.1} deg) scores {}",
                self.best_score
            ));
        }
        // A positive best without a rival leads by 100 %: never refused.
        let r = self.rival.as_ref()?;
        let d = self.best.inverse() * r;
        Some(format!(
            "ambiguous: the best pose (x {x:.2} m, y {y:.2} m, {deg:.1} deg) scores {}, a pose {:.0} deg and {:.1} m \
             away (x {:.2} m, y {:.2} m, {:.1} deg) scores {} ({:.0}% of it); the best must lead by {:.0}%",
            self.best_score,
            d.rotation.angle().to_degrees().abs(),
            d.translation.vector.norm(),
            r.translation.x,
            r.translation.y,
            r.rotation.angle().to_degrees(),
            self.rival_score,
            100.0 * self.rival_score as f64 / self.best_score.max(1) as f64,
            100.0 * min_margin
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mrslam_core::pose;
    use std::f64::consts::PI;

    #[test]
    fn the_margin_is_the_winners_lead_over_its_rival() {
        let s = |best, rival: Option<i64>| Significance {
            best: Pose2::identity(),
            best_score: best,
            rival: rival.map(|_| pose(1.0, 2.0, PI)),
            rival_score: rival.unwrap_or(0),
        };
        assert!((s(1000, Some(900)).margin() - 0.1).abs() < 1e-12);
        assert_eq!(s(1000, Some(-50)).margin(), 1.0);
        assert_eq!(s(1000, None).margin(), 1.0);
        assert_eq!(s(-10, None).margin(), 0.0);
        assert!(s(1000, Some(900)).refusal(0.0).is_none());
        assert!(s(1000, Some(900)).refusal(0.05).is_none());
        let why = s(1000, Some(900)).refusal(0.15).unwrap();
        assert!(why.contains("180 deg") && why.contains("90% of it") && why.contains("lead by 15%"), "{why}");
    }
}
