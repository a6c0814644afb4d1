//! Wheel samples from whichever message the robot file's `[wheels]` names:
//! JointState positions (else velocities) of the named joints, the body
//! twist of a `nav_msgs/Odometry` turned back into wheel rates with the
//! nominal robot, or encoder tick counters unwrapped across their wraparound.

use super::options::ReadOptions;
use super::ros_msgs::{JointStateMsg, OdometryMsg};
use crate::recording::WheelValues;
use crate::robot::WheelSourceKind;

/// Wheel readings before sorting: angles, or rates to integrate.
#[derive(Debug, Clone, Copy, PartialEq)]
enum WheelMode {
    Positions,
    Velocities,
}

/// One tick counter followed across its wraparound, from 0 at its first
/// reading: each reading moves the total by the difference to the previous
/// reading taken modulo 2^bits into [−2^(bits−1), 2^(bits−1)), so a counter
/// that wraps (or a signed one that overflows) keeps counting, as long as it
/// moves less than half its range between two messages.
#[derive(Debug, Default)]
struct Unwrap {
    last: Option<i128>,
    total: i128,
}

impl Unwrap {
    fn push(&mut self, raw: i128, bits: u32) -> i128 {
        let range = 1i128 << bits;
        match self.last {
            None => self.total = 0,
            Some(last) => {
                let d = (raw - last).rem_euclid(range);
                self.total += if d >= range / 2 { d - range } else { d };
            }
        }
        self.last = Some(raw);
        self.total
    }
}

/// Turns wheel messages into (left, right) values: angles (rad), or rates
/// (rad/s) for [`Self::rates`], remembering what the messages carried.
#[derive(Debug, Default)]
pub(crate) struct WheelDecoder {
    mode: Option<WheelMode>,
    values: Option<WheelValues>,
    ticks: [Unwrap; 2],
    messages: usize,
    /// Whether any twist was non-zero.
    moved: bool,
}

impl WheelDecoder {
    /// Whether the values are rates (rad/s) to integrate, not angles.
    pub(crate) fn rates(&self) -> bool {
        self.mode == Some(WheelMode::Velocities)
    }

    /// What the messages carried, once one was decoded.
    pub(crate) fn values(&self) -> Option<WheelValues> {
        self.values
    }

    /// The wheel joints' positions, or velocities when the first message has
    /// no positions (the choice then holds for the whole topic).
    pub(crate) fn joint_state(
        &mut self,
        m: &JointStateMsg,
        opts: &ReadOptions,
    ) -> Result<(f64, f64), String> {
        let il = joint_index(m, &opts.left_joint)?;
        let ir = joint_index(m, &opts.right_joint)?;
        let has = |v: &Vec<f64>| v.len() == m.name.len();
        let mode = *self.mode.get_or_insert(if has(&m.position) {
            WheelMode::Positions
        } else {
            WheelMode::Velocities
        });
        let values = match mode {
            WheelMode::Positions if has(&m.position) => &m.position,
            WheelMode::Velocities if has(&m.velocity) => &m.velocity,
            _ => {
                return Err(format!(
                    "JointState has {} positions and {} velocities for {} names; \
                     the wheel {} are needed",
                    m.position.len(),
                    m.velocity.len(),
                    m.name.len(),
                    if mode == WheelMode::Positions {
                        "positions"
                    } else {
                        "velocities"
                    }
                ))
            }
        };
        self.note(match mode {
            WheelMode::Positions => WheelValues::Positions,
            WheelMode::Velocities => WheelValues::Velocities,
        });
        finite("wheel joint value", values[il], values[ir])
    }

    /// Wheel rates (rad/s) from the odometry's body twist in its child frame
    /// (V = linear.x m/s, W = angular.z rad/s) with the nominal kinematics:
    /// ω_R = (V + W·D/2)/R_R, ω_L = (V − W·D/2)/R_L. A controller that
    /// computed the twist from its wheels with these same R_R, R_L, D
    /// (`V = (R_R ω_R + R_L ω_L)/2`, `W = (R_R ω_R − R_L ω_L)/D`) gives back
    /// exactly the rates its encoders measured.
    pub(crate) fn twist(
        &mut self,
        m: &OdometryMsg,
        opts: &ReadOptions,
    ) -> Result<(f64, f64), String> {
        let (v, w) = (m.linear.x, m.angular.z);
        if !(v.is_finite() && w.is_finite()) {
            return Err(format!("non-finite twist: linear.x {v}, angular.z {w}"));
        }
        self.mode = Some(WheelMode::Velocities);
        self.note(WheelValues::Twist);
        self.moved |= v != 0.0 || w != 0.0;
        let (right, left) = opts.nominal.wheel_rates(v, w);
        finite("wheel rate from the twist", left, right)
    }

    /// Wheel angles (rad) from the counters `data[left_index]` and
    /// `data[right_index]`, unwrapped at the configured width, times
    /// 2π / ticks_per_rev, from 0 at the first message.
    pub(crate) fn ticks(
        &mut self,
        data: &[i128],
        opts: &ReadOptions,
    ) -> Result<(f64, f64), String> {
        let layout = opts
            .wheels
            .ticks_layout()
            .ok_or("[wheels] source = \"ticks\" without ticks_type")?;
        let pick = |i: usize, key: &str| -> Result<i128, String> {
            let raw = *data.get(i).ok_or_else(|| {
                format!(
                    "the tick array has {} elements, and [wheels] {key} = {i} is beyond them",
                    data.len()
                )
            })?;
            let bits = layout.wrap_bits;
            if bits < layout.ticks_type.bits()
                && !(-(1i128 << (bits - 1))..1i128 << bits).contains(&raw)
            {
                return Err(format!(
                    "tick counter {raw} (data[{i}]) does not fit the {bits}-bit counter that \
                     [wheels] ticks_wrap_bits = {bits} declares"
                ));
            }
            Ok(raw)
        };
        let (l, r) = (
            pick(layout.left_index, "left_index")?,
            pick(layout.right_index, "right_index")?,
        );
        self.mode = Some(WheelMode::Positions);
        self.note(WheelValues::Ticks);
        let rad = 2.0 * std::f64::consts::PI / opts.ticks_per_rev;
        let left = self.ticks[0].push(l, layout.wrap_bits) as f64 * rad;
        let right = self.ticks[1].push(r, layout.wrap_bits) as f64 * rad;
        finite("wheel angle from the ticks", left, right)
    }

    fn note(&mut self, v: WheelValues) {
        self.values = Some(v);
        self.messages += 1;
    }

    /// What the whole topic shows that no single message does: an odometry
    /// whose twist is zero in every message carries poses only.
    pub(crate) fn check_end(&self, opts: &ReadOptions) -> Result<(), String> {
        if opts.wheels.source == WheelSourceKind::Odometry && self.messages >= 2 && !self.moved {
            return Err(format!(
                "the twist is zero in all {} messages: this odometry carries poses only, and \
                 the robot file's [wheels] source = \"odometry\" reads the wheels from the twist \
                 (V, W). Name the topic with the wheel joints or encoder ticks in [wheels] \
                 source and topic instead (`odocal inspect REC` lists the topics)",
                self.messages
            ));
        }
        Ok(())
    }
}

/// The index of joint `name`, or an error listing the names the message has
/// and the robot-file keys that name the wheel joints.
fn joint_index(m: &JointStateMsg, name: &str) -> Result<usize, String> {
    m.name.iter().position(|n| n == name).ok_or_else(|| {
        format!(
            "JointState has no joint '{name}' (its joints: {:?}); set left_joint and \
             right_joint in the robot file (--robot ROBOT.toml) to the wheel joints' names, \
             or [wheels] source and topic when the wheels are reported elsewhere \
             (`odocal inspect REC` proposes them)",
            m.name
        )
    })
}

fn finite(what: &str, left: f64, right: f64) -> Result<(f64, f64), String> {
    if left.is_finite() && right.is_finite() {
        Ok((left, right))
    } else {
        Err(format!("non-finite {what}: [{left}, {right}]"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::{RobotConfig, TicksType, WheelsConfig};

    fn ticks_opts(ty: TicksType, bits: Option<u32>) -> ReadOptions {
        let robot = RobotConfig {
            ticks_per_rev: 4.0,
            wheels: WheelsConfig {
                source: WheelSourceKind::Ticks,
                topic: Some("/ticks".into()),
                ticks_type: Some(ty),
                right_index: Some(0),
                left_index: Some(2),
                ticks_wrap_bits: bits,
            },
            ..RobotConfig::default()
        };
        ReadOptions::for_robot(&robot)
    }

    #[test]
    fn counters_are_unwrapped_across_16_32_and_64_bits() {
        // A 16-bit counter in an Int32MultiArray, unsigned 0..65535: +3 ticks
        // across the wrap, then back −5 (a quarter turn per tick).
        let o = ticks_opts(TicksType::Int32MultiArray, Some(16));
        let mut d = WheelDecoder::default();
        let quarter = std::f64::consts::FRAC_PI_2;
        assert_eq!(d.ticks(&[9, 0, 65534], &o).unwrap(), (0.0, 0.0));
        assert_eq!(d.ticks(&[9, 0, 1], &o).unwrap().0, 3.0 * quarter);
        assert_eq!(
            d.ticks(&[8, 0, 65532], &o).unwrap(),
            (-2.0 * quarter, -quarter)
        );
        assert!(d
            .ticks(&[0, 0, 70000], &o)
            .unwrap_err()
            .contains("ticks_wrap_bits"));
        // A signed 32-bit counter overflowing from i32::MAX to i32::MIN: +1.
        let o = ticks_opts(TicksType::Int32MultiArray, None);
        let mut d = WheelDecoder::default();
        d.ticks(&[i32::MAX as i128, 0, 0], &o).unwrap();
        assert_eq!(d.ticks(&[i32::MIN as i128, 0, 0], &o).unwrap().1, quarter);
        assert!(d.ticks(&[0, 0], &o).unwrap_err().contains("left_index = 2"));
        assert_eq!(d.values(), Some(WheelValues::Ticks));
        // An unsigned 64-bit counter wrapping to 0 moves by +1, and back by −2.
        let mut u = Unwrap::default();
        u.push(u64::MAX as i128, 64);
        assert_eq!(u.push(0, 64), 1);
        assert_eq!(u.push((u64::MAX - 1) as i128, 64), -1);
    }

    #[test]
    fn a_twist_gives_back_the_rates_its_controller_measured() {
        // By hand: R_R = 0.1, R_L = 0.2, D = 0.5; ω_R = 2, ω_L = 3 rad/s give
        // V = (0.2 + 0.6)/2 = 0.4 m/s, W = (0.2 − 0.6)/0.5 = −0.8 rad/s.
        let mut o = ReadOptions::default();
        o.wheels.source = WheelSourceKind::Odometry;
        o.nominal = crate::robot::DiffDrive {
            r_right: 0.1,
            r_left: 0.2,
            wheel_base: 0.5,
        };
        let mut m = OdometryMsg::default();
        m.linear.x = 0.4;
        m.angular.z = -0.8;
        let mut d = WheelDecoder::default();
        let (l, r) = d.twist(&m, &o).unwrap();
        assert!(
            (l - 3.0).abs() < 1e-12 && (r - 2.0).abs() < 1e-12,
            "{l} {r}"
        );
        assert!(d.rates() && d.check_end(&o).is_ok());
        let mut still = WheelDecoder::default();
        for _ in 0..3 {
            still.twist(&OdometryMsg::default(), &o).unwrap();
        }
        assert!(still.check_end(&o).unwrap_err().contains("zero in all 3"));
    }

    #[test]
    fn missing_joints_name_the_joints_found_and_the_keys() {
        let m = JointStateMsg {
            name: vec!["wheel_l_joint".into(), "wheel_r_joint".into()],
            position: vec![0.0, 0.0],
            ..Default::default()
        };
        let e = WheelDecoder::default()
            .joint_state(&m, &ReadOptions::default())
            .unwrap_err();
        for word in ["wheel_l_joint", "left_joint", "right_joint", "'left_wheel'"] {
            assert!(e.contains(word), "{e}");
        }
    }
}
