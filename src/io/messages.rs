//! ROS 2 messages arriving one at a time, in arrival order, from no file: a
//! robot's topics received over the network. Each message is decoded by the
//! bag readers' own code (`io::mcap_streams`: stamps, the time-order
//! check, the wheels from the source the robot file names, scan checks), and
//! each stream is released in stamp order once it has gone the reorder
//! tolerance past a sample, as a bag's streams are (at once with no
//! tolerance). A message that fails is
//! refused on its own; the decoder goes on with the next.

use std::collections::{HashMap, VecDeque};

pub use super::mcap_streams::StreamMount;
use super::mcap_streams::{released, roles_for, RateIntegrator, Role, State, Wire};
use super::options::ReadOptions;
use super::reorder::Reorder;
use super::source::Item;
use crate::error::InputError;
use crate::recording::WheelValues;

/// Messages in, samples out.
pub struct MessageDecoder<'o> {
    opts: &'o ReadOptions,
    state: State<'o>,
    /// Topic → the roles its messages play.
    roles: HashMap<String, Vec<Role>>,
    buffers: [Reorder; 5],
    rates: Option<RateIntegrator>,
    ready: VecDeque<Item>,
    /// Samples decoded from each stream.
    decoded: [usize; 5],
}

impl<'o> MessageDecoder<'o> {
    /// A decoder for the streams `opts` names; `name` says where the
    /// messages come from, in errors.
    pub fn new(name: &str, opts: &'o ReadOptions) -> Self {
        Self {
            opts,
            state: State::new(name, opts),
            roles: HashMap::new(),
            buffers: Default::default(),
            rates: None,
            ready: VecDeque::new(),
            decoded: [0; 5],
        }
    }

    /// Declares `topic`, whose messages have type `type_name`
    /// (`pkg/msg/Type`): `true` when it carries a stream of `opts`; an error
    /// when it is a configured topic of another type.
    pub fn declare(&mut self, topic: &str, type_name: &str) -> Result<bool, String> {
        let roles = roles_for(topic, type_name, "cdr", Wire::Cdr, self.opts)?;
        let any = !roles.is_empty();
        if any {
            self.roles.insert(topic.to_string(), roles);
        }
        Ok(any)
    }

    /// Decodes one CDR message (encapsulation header included) of a
    /// declared topic; `log_time_ns` stands in for an unset header stamp
    /// (and stamps tick counters, which have none). A message of an
    /// undeclared topic is ignored.
    pub fn push(&mut self, topic: &str, data: &[u8], log_time_ns: u64) -> Result<(), String> {
        let Some(roles) = self.roles.get(topic) else {
            return Ok(());
        };
        for role in roles {
            self.state.handle(*role, data, log_time_ns)?;
        }
        let rec = self.state.decoded();
        let mut fresh: Vec<Item> = rec.scans.drain(..).map(Item::Scan).collect();
        fresh.extend(rec.wheels.drain(..).map(Item::Wheel));
        fresh.extend(rec.gyro.drain(..).map(Item::Gyro));
        fresh.extend(rec.odom.drain(..).map(Item::Odom));
        fresh.extend(rec.reference.drain(..).map(Item::Reference));
        let tolerance = self.opts.reorder_tolerance;
        for item in fresh {
            let s = item.stream();
            self.decoded[s] += 1;
            // No tolerance: the time-order check refused anything earlier
            // than its stream's latest, so each sample goes out at once.
            if tolerance <= 0.0 {
                self.release(item);
                continue;
            }
            self.buffers[s].insert(item);
            while let Some(i) = self.buffers[s].pop_ready(tolerance) {
                self.release(i);
            }
        }
        Ok(())
    }

    /// The next sample released, in each stream's stamp order.
    pub fn pop(&mut self) -> Option<Item> {
        self.ready.pop_front()
    }

    /// Releases every sample held (the input has ended).
    pub fn flush(&mut self) {
        for b in 0..self.buffers.len() {
            while let Some(item) = self.buffers[b].items.pop_front() {
                self.release(item);
            }
        }
    }

    /// Samples decoded so far per stream: scans, wheels, gyro, odometry,
    /// reference.
    pub fn decoded(&self) -> [usize; 5] {
        self.decoded
    }

    /// The laser mounting the transforms decoded so far state, with its
    /// origin, or why there is none.
    pub fn mount(&mut self) -> Result<StreamMount, InputError> {
        self.state.mount_so_far()
    }

    /// How the wheel messages give the angles, once one was decoded.
    pub fn wheel_values(&self) -> Option<WheelValues> {
        self.state.wheel_values()
    }

    fn release(&mut self, item: Item) {
        let item = released(item, self.state.wheel_rates(), &mut self.rates);
        self.ready.push_back(item);
    }
}
