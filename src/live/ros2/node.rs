//! The node: a participant on the domain (on 127.0.0.1 only when asked),
//! a ROS 2 node whose spinner serves the parameter services, raw readers
//! and writers for the robot's topics, and typed publishers for what odocal
//! says.

use std::net::IpAddr;

use ros2_client::dds::rustdds::{
    self, no_key, policy, DomainParticipant, DomainParticipantBuilder, QosPolicies,
    QosPolicyBuilder, TopicKind,
};
use ros2_client::{
    Context, MessageTypeName, Name, Node, NodeName, NodeOptions, ParameterValue, Publisher,
    QosProfile,
};
use serde::Serialize;

use super::raw::{RawAdapter, RawCdr};
use super::{dds_topic, dds_type, Ros2Error};

/// The node parameters a live run sets: the multipliers of ros2_control's
/// `diff_drive_controller`, and one radius multiplier for controllers with
/// a single one.
pub const PARAMETERS: [&str; 4] = [
    "left_wheel_radius_multiplier",
    "right_wheel_radius_multiplier",
    "wheel_separation_multiplier",
    "wheel_radius_multiplier",
];

/// A raw reader of one topic.
pub type RawReader = no_key::DataReader<RawCdr, RawAdapter>;
/// A raw writer of one topic.
pub type RawWriter = no_key::DataWriter<RawCdr, RawAdapter>;

/// A ROS 2 node on a DDS domain.
pub struct Ros2Node {
    participant: DomainParticipant,
    context: Context,
    node: Node,
    subscriber: rustdds::Subscriber,
    publisher: rustdds::Publisher,
}

/// QoS of a sensor stream's reader: best effort, which also matches
/// reliable writers, so that both kinds of publisher are heard.
pub fn sensor_qos(depth: i32) -> QosPolicies {
    QosPolicyBuilder::new()
        .reliability(policy::Reliability::BestEffort)
        .durability(policy::Durability::Volatile)
        .history(policy::History::KeepLast { depth })
        .build()
}

/// QoS of `/tf_static` (ROS 2's latched transforms): reliable,
/// transient-local, depth 100.
pub fn latched_qos() -> QosPolicies {
    QosPolicyBuilder::new()
        .reliability(policy::Reliability::Reliable {
            max_blocking_time: rustdds::Duration::from_millis(100),
        })
        .durability(policy::Durability::TransientLocal)
        .history(policy::History::KeepLast { depth: 100 })
        .build()
}

/// QoS of a reliable stream written by odocal (ROS 2's default: reliable,
/// volatile, depth `depth`).
pub fn reliable_qos(depth: i32) -> QosPolicies {
    QosPolicyBuilder::new()
        .reliability(policy::Reliability::Reliable {
            max_blocking_time: rustdds::Duration::from_millis(100),
        })
        .durability(policy::Durability::Volatile)
        .history(policy::History::KeepLast { depth })
        .build()
}

impl Ros2Node {
    /// Joins `domain` as node `/name` (127.0.0.1 only with `localhost`),
    /// with [`PARAMETERS`] declared (unset until there is an estimate) when
    /// `parameters`.
    pub fn join(
        name: &str,
        domain: u16,
        localhost: bool,
        parameters: bool,
    ) -> Result<Self, Ros2Error> {
        let mut builder = DomainParticipantBuilder::new(domain);
        if localhost {
            builder = builder.with_only_networks([IpAddr::from([127, 0, 0, 1])]);
        }
        let participant = builder.build().map_err(Ros2Error::dds)?;
        let context =
            Context::from_domain_participant(participant.clone()).map_err(Ros2Error::dds)?;
        let mut options = NodeOptions::new()
            .enable_rosout(false)
            .start_parameter_services(parameters);
        if parameters {
            for p in PARAMETERS {
                options = options.declare_parameter(p, ParameterValue::NotSet);
            }
        }
        let node_name = NodeName::new("/", name).map_err(|e| Ros2Error::Name {
            name: name.to_string(),
            why: format!("{e:?}"),
        })?;
        let node = context
            .new_node(node_name, options)
            .map_err(|e| Ros2Error::Dds(format!("{e:?}")))?;
        let qos = QosPolicies::qos_none();
        let subscriber = participant
            .create_subscriber(&qos)
            .map_err(Ros2Error::dds)?;
        let publisher = participant.create_publisher(&qos).map_err(Ros2Error::dds)?;
        Ok(Self {
            participant,
            context,
            node,
            subscriber,
            publisher,
        })
    }

    /// The domain joined.
    pub fn domain(&self) -> u16 {
        self.context.domain_id()
    }

    /// The DDS topic of ROS topic `topic` with ROS type `ros_type`.
    fn topic(
        &self,
        topic: &str,
        ros_type: &str,
        qos: &QosPolicies,
    ) -> Result<rustdds::Topic, Ros2Error> {
        self.participant
            .create_topic(dds_topic(topic)?, dds_type(ros_type), qos, TopicKind::NoKey)
            .map_err(Ros2Error::dds)
    }

    /// A reader handing over `topic`'s payloads undecoded.
    pub fn raw_reader(
        &self,
        topic: &str,
        ros_type: &str,
        qos: QosPolicies,
    ) -> Result<RawReader, Ros2Error> {
        let t = self.topic(topic, ros_type, &qos)?;
        self.subscriber
            .create_datareader_no_key::<RawCdr, RawAdapter>(&t, Some(qos))
            .map_err(Ros2Error::dds)
    }

    /// A writer sending payloads already encoded on `topic`.
    pub fn raw_writer(
        &self,
        topic: &str,
        ros_type: &str,
        qos: QosPolicies,
    ) -> Result<RawWriter, Ros2Error> {
        let t = self.topic(topic, ros_type, &qos)?;
        self.publisher
            .create_datawriter_no_key::<RawCdr, RawAdapter>(&t, Some(qos))
            .map_err(Ros2Error::dds)
    }

    /// A typed publisher of `topic` (`pkg`, `name`: the ROS type) with ROS
    /// 2's default publisher QoS and `depth`.
    pub fn publisher<M: Serialize>(
        &mut self,
        topic: &str,
        (pkg, name): (&str, &str),
        depth: i32,
    ) -> Result<Publisher<M>, Ros2Error> {
        let ros_name = Name::parse(topic).map_err(|e| Ros2Error::Name {
            name: topic.to_string(),
            why: format!("{e:?}"),
        })?;
        let qos = QosProfile::publisher_default().history(ros2_client::qos::History::KeepLast {
            depth: depth.max(1) as usize,
        });
        let t = self
            .node
            .create_topic(&ros_name, MessageTypeName::new(pkg, name), &qos)
            .map_err(Ros2Error::dds)?;
        self.node
            .create_publisher::<M>(&t, None)
            .map_err(Ros2Error::dds)
    }

    /// Starts the node's spinner (parameter services, graph updates) on a
    /// thread of its own; it runs until the node is dropped.
    pub fn spin(&mut self) -> Result<std::thread::JoinHandle<()>, Ros2Error> {
        let spinner = self.node.spinner().map_err(Ros2Error::dds)?;
        std::thread::Builder::new()
            .name("ros2-spinner".into())
            .spawn(move || {
                // Ends with an error only when the node is gone.
                let _ = futures::executor::block_on(spinner.spin());
            })
            .map_err(Ros2Error::dds)
    }

    /// Sets a declared parameter to `value`.
    pub fn set_parameter(&self, name: &str, value: f64) -> Result<(), Ros2Error> {
        self.node
            .set_parameter(name, ParameterValue::Double(value))
            .map_err(Ros2Error::Dds)
    }

    /// A declared parameter's value (`None` while unset).
    pub fn parameter(&self, name: &str) -> Option<f64> {
        match self.node.get_parameter(name) {
            Some(ParameterValue::Double(v)) => Some(v),
            _ => None,
        }
    }

    /// How many writers of `topic` (a ROS name) the node has discovered.
    pub fn publishers_of(&self, topic: &str) -> usize {
        self.node.publisher_count(topic)
    }

    /// Stops the spinner.
    pub fn stop(&self) {
        self.node.stop_spinner();
    }
}
