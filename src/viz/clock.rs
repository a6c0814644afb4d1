//! Which scan a time belongs to, learnt from the scans logged: things logged
//! with a time only (a trajectory's poses) are placed on the `scan` timeline
//! too, at the last scan at or before their time, so they move with the
//! scan cursor as they do with the time cursor.
//!
//! At most `cap` scans are remembered; past that every other is forgotten
//! and only every 2k-th scan is noted from then on, so a time is placed at
//! a scan up to `stride() − 1` scans early (never late).

/// The (time, scan) pairs of the scans logged, thinned past a cap.
#[derive(Debug, Clone)]
pub struct ScanClock {
    times: Vec<f64>,
    scans: Vec<i64>,
    stride: usize,
    seen: usize,
    cap: usize,
}

impl ScanClock {
    /// A clock remembering at most `cap` (≥ 2) scans.
    pub fn new(cap: usize) -> Self {
        Self {
            times: Vec::new(),
            scans: Vec::new(),
            stride: 1,
            seen: 0,
            cap: cap.max(2),
        }
    }

    /// Notes scan `scan` at `time` (s); times that do not increase are ignored.
    pub fn note(&mut self, time: f64, scan: i64) {
        if !time.is_finite() || self.times.last().is_some_and(|&l| time <= l) {
            return;
        }
        let take = self.seen.is_multiple_of(self.stride);
        self.seen += 1;
        if !take {
            return;
        }
        self.times.push(time);
        self.scans.push(scan);
        if self.times.len() >= self.cap {
            self.times = self.times.iter().step_by(2).copied().collect();
            self.scans = self.scans.iter().step_by(2).copied().collect();
            self.stride *= 2;
        }
    }

    /// Whether no scan was noted.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// Every k-th scan is remembered (1 until the cap was reached).
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// The scan of the last remembered scan at or before `time` (s); the
    /// first scan's for earlier times; `None` before any scan was noted.
    pub fn scan_at(&self, time: f64) -> Option<i64> {
        let i = self.times.partition_point(|&t| t <= time);
        self.scans.get(i.saturating_sub(1)).copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_time_falls_on_the_last_scan_before_it() {
        let mut c = ScanClock::new(1000);
        assert_eq!(c.scan_at(1.0), None);
        for i in 0..10 {
            c.note(10.0 + 0.1 * i as f64, i + 5);
        }
        c.note(10.05, 99); // back in time: ignored
        assert_eq!(c.scan_at(10.0), Some(5));
        assert_eq!(c.scan_at(10.25), Some(7));
        assert_eq!(c.scan_at(3.0), Some(5));
        assert_eq!(c.scan_at(99.0), Some(14));
    }

    #[test]
    fn past_the_cap_a_time_is_placed_at_most_a_stride_early() {
        let mut c = ScanClock::new(16);
        for i in 0..1000 {
            c.note(i as f64, i);
        }
        let s = c.stride() as i64;
        assert!(s > 1 && s <= 128, "{s}");
        for i in 0..1000 {
            let at = c.scan_at(i as f64 + 0.5).unwrap();
            assert!(at <= i && i - at < s, "{i} → {at} (stride {s})");
        }
    }
}
