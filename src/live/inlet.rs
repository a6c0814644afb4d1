//! Between the network and the calibration: a bounded queue of raw
//! messages. The network side never waits (a message arriving when the
//! queue is full is dropped, as is one larger than allowed), and every
//! drop is counted, so a calibration that falls behind costs messages, not
//! memory.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError};
use std::sync::Arc;
use std::time::Instant;

/// One message as it came off the network.
#[derive(Debug, Clone)]
pub struct Incoming {
    /// The ROS topic (`/scan`).
    pub topic: String,
    /// The CDR payload with its 4-byte encapsulation header.
    pub data: Vec<u8>,
    /// The writer's source timestamp (ns since the epoch), else the
    /// arrival's: the stand-in for an unset header stamp, as a bag's log
    /// time is.
    pub log_time_ns: u64,
    /// When it arrived.
    pub arrived: Instant,
}

/// Counts of what came in, shared by both sides.
#[derive(Debug, Default)]
pub struct InletStats {
    /// Messages queued.
    pub queued: AtomicU64,
    /// Messages dropped because the queue was full.
    pub dropped_full: AtomicU64,
    /// Messages refused for their size.
    pub oversized: AtomicU64,
    /// Messages the decoder refused (malformed, of the wrong type, out of
    /// time order).
    pub refused: AtomicU64,
}

impl InletStats {
    fn bump(c: &AtomicU64) {
        c.fetch_add(1, Ordering::Relaxed);
    }

    /// Counts a message the decoder refused.
    pub fn refuse(&self) {
        Self::bump(&self.refused);
    }

    /// (queued, dropped because full, oversized, refused).
    pub fn counts(&self) -> [u64; 4] {
        [
            self.queued.load(Ordering::Relaxed),
            self.dropped_full.load(Ordering::Relaxed),
            self.oversized.load(Ordering::Relaxed),
            self.refused.load(Ordering::Relaxed),
        ]
    }
}

/// The network's end of the queue.
#[derive(Debug, Clone)]
pub struct Inlet {
    tx: SyncSender<Incoming>,
    stats: Arc<InletStats>,
    max_bytes: usize,
}

impl Inlet {
    /// A queue of `capacity` messages of at most `max_bytes` each: the
    /// inlet, its other end, and the shared counts.
    pub fn new(capacity: usize, max_bytes: usize) -> (Self, Receiver<Incoming>, Arc<InletStats>) {
        let (tx, rx) = std::sync::mpsc::sync_channel(capacity.max(1));
        let stats = Arc::new(InletStats::default());
        let inlet = Self {
            tx,
            stats: stats.clone(),
            max_bytes,
        };
        (inlet, rx, stats)
    }

    /// Queues `m` unless it is too large or the queue is full (both
    /// counted); `false` once the other end is gone.
    pub fn offer(&self, m: Incoming) -> bool {
        if m.data.len() > self.max_bytes {
            InletStats::bump(&self.stats.oversized);
            return true;
        }
        match self.tx.try_send(m) {
            Ok(()) => {
                InletStats::bump(&self.stats.queued);
                true
            }
            Err(TrySendError::Full(_)) => {
                InletStats::bump(&self.stats.dropped_full);
                true
            }
            Err(TrySendError::Disconnected(_)) => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn msg(n: usize) -> Incoming {
        Incoming {
            topic: "/scan".into(),
            data: vec![0; n],
            log_time_ns: 0,
            arrived: Instant::now(),
        }
    }

    #[test]
    fn a_full_queue_drops_and_counts_instead_of_growing() {
        let (inlet, rx, stats) = Inlet::new(3, 100);
        for _ in 0..10 {
            assert!(inlet.offer(msg(10)));
        }
        assert!(inlet.offer(msg(101)));
        assert_eq!(stats.counts(), [3, 7, 1, 0]);
        assert_eq!(rx.try_iter().count(), 3);
        drop(rx);
        assert!(!inlet.offer(msg(1)));
    }
}
