//! The IMU topic of a bag or MCAP file, as `--imu` asks for it: `auto` takes the only
//! `sensor_msgs/Imu` topic (none is no IMU, several is an error naming them), a topic name
//! takes that topic. Its messages are read once when the file is opened (a sample takes 56
//! bytes, an hour at 200 Hz 40 MB) and handed on with the frames by
//! [`WithImu`](crate::imu::attach::WithImu). A message that cannot be read is left out, counted
//! and named in one dataset warning; samples are used in stamp order.

use super::imu_msg::ImuError;
use super::pointcloud2::{choose_topic, wanted_topics, Wanted};
use crate::dataset::ImuInput;
use crate::imu::ImuSample;

/// The IMU topic to read, if any: `None` when `input` asks for none from the file, or for
/// `auto` and the file has no topic of `type_name` (which `is_imu` recognises).
pub(crate) fn choose(
    file: &str,
    topics: &[(String, String)],
    is_imu: impl Fn(&str) -> bool,
    type_name: &str,
    input: &ImuInput,
) -> Result<Option<String>, String> {
    let wanted = Wanted {
        type_name,
        kind: "IMU",
        flag: "--imu TOPIC",
    };
    match input {
        ImuInput::Builtin | ImuInput::File(_) => Ok(None),
        ImuInput::Auto if wanted_topics(topics, &is_imu).is_empty() => Ok(None),
        ImuInput::Auto => choose_topic(file, topics, is_imu, wanted, None).map(Some),
        ImuInput::Topic(t) => choose_topic(file, topics, is_imu, wanted, Some(t)).map(Some),
    }
}

/// Gathers the samples of one topic's messages, in receive order, and what went wrong.
pub(crate) struct Collector<'a> {
    file: &'a str,
    topic: &'a str,
    samples: Vec<ImuSample>,
    /// Messages left out, and the first of them with its reason.
    refused: usize,
    first_refused: Option<String>,
    /// Where a damaged container stopped the reading.
    stopped: Option<String>,
}

impl<'a> Collector<'a> {
    /// An empty collection for `topic` of `file`.
    pub fn new(file: &'a str, topic: &'a str) -> Self {
        Self {
            file,
            topic,
            samples: Vec::new(),
            refused: 0,
            first_refused: None,
            stopped: None,
        }
    }

    /// Message `index` (in receive order), parsed.
    pub fn push(&mut self, index: usize, parsed: Result<ImuSample, ImuError>) {
        match parsed {
            Ok(s) => self.samples.push(s),
            Err(e) => self.refuse(index, &e),
        }
    }

    /// Message `index` cannot be used, for `reason`.
    pub fn refuse(&mut self, index: usize, reason: &dyn std::fmt::Display) {
        self.refused += 1;
        if self.first_refused.is_none() {
            self.first_refused = Some(format!("message {index}: {reason}"));
        }
    }

    /// The container is damaged at message `index`: nothing after it is read.
    pub fn stop(&mut self, index: usize, reason: &dyn std::fmt::Display) {
        self.stopped = Some(format!(
            "message {index} cannot be read ({reason}); the messages after it in the file were not read"
        ));
    }

    /// The samples in stamp order, and the warnings about them in `warnings`.
    pub fn finish(mut self, warnings: &mut Vec<String>) -> Vec<ImuSample> {
        let (file, topic) = (self.file, self.topic);
        if let Some(first) = &self.first_refused {
            warnings.push(format!(
                "{file}: {} message(s) on {topic} could not be read and were left out \
                 (first: {first})",
                self.refused
            ));
        }
        if let Some(stopped) = &self.stopped {
            warnings.push(format!("{file}: IMU topic {topic}: {stopped}"));
        }
        if self.samples.windows(2).any(|w| w[1].time_ns < w[0].time_ns) {
            warnings.push(format!(
                "{file}: the stamps on {topic} are not in receive order; the samples are used \
                 in stamp order"
            ));
            self.samples.sort_by_key(|s| s.time_ns);
        }
        self.samples
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn topics() -> Vec<(String, String)> {
        [("/points", "PC2"), ("/imu", "Imu"), ("/imu2", "Imu")]
            .iter()
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .collect()
    }

    #[test]
    fn auto_takes_the_only_imu_topic_and_a_name_must_exist() {
        let imu = |t: &str| t == "Imu";
        let all = topics();
        let one = &all[..2];
        let choose =
            |topics: &[(String, String)], input: ImuInput| choose("f", topics, imu, "Imu", &input);
        assert_eq!(choose(one, ImuInput::Auto), Ok(Some("/imu".into())));
        assert_eq!(choose(&all[..1], ImuInput::Auto), Ok(None));
        assert_eq!(choose(one, ImuInput::Builtin), Ok(None));
        let e = choose(&all, ImuInput::Auto).unwrap_err();
        assert!(
            e.contains("/imu, /imu2") && e.contains("--imu TOPIC"),
            "{e}"
        );
        let named = choose(&all, ImuInput::Topic("/imu2".into()));
        assert_eq!(named, Ok(Some("/imu2".into())));
        let e = choose(&all, ImuInput::Topic("/nope".into())).unwrap_err();
        assert!(
            e.contains("no topic /nope (IMU topics: /imu, /imu2)"),
            "{e}"
        );
        let e = choose(&all, ImuInput::Topic("/points".into())).unwrap_err();
        assert!(e.contains("/points carries PC2, not Imu"), "{e}");
    }

    #[test]
    fn refused_messages_are_counted_and_samples_put_in_stamp_order() {
        let at = |ns| ImuSample {
            time_ns: ns,
            ..ImuSample::default()
        };
        let mut c = Collector::new("f.bag", "/imu");
        c.push(0, Ok(at(20)));
        c.push(1, Err(ImuError::Trailing(4)));
        c.push(2, Ok(at(10)));
        c.push(3, Err(ImuError::Stamp));
        let mut warnings = Vec::new();
        let samples = c.finish(&mut warnings);
        assert_eq!(samples, vec![at(10), at(20)]);
        assert_eq!(warnings.len(), 2, "{warnings:?}");
        assert!(
            warnings[0].contains("2 message(s) on /imu")
                && warnings[0].contains("message 1: 4 bytes after"),
            "{}",
            warnings[0]
        );
        assert!(warnings[1].contains("stamp order"), "{}", warnings[1]);
    }
}
