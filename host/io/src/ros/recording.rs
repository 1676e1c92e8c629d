//! A ROS recording as the frame readers see it, whatever its container: a ROS 1 bag, an MCAP
//! file or a ROS 2 sqlite3 bag each implement [`Recording`], which lists the topics and hands
//! out the messages of some of them, one at a time ([`MessageStream`]). What the messages
//! become (clouds, packets decoded into sweeps, Livox points, IMU samples) is
//! [`frames`](super::frames)' to decide, the same for every container.

use crate::dataset::Format;
use anyhow::Result;
use std::ops::ControlFlow;

/// One message of a recording, borrowed from the stream that read it.
#[derive(Clone, Debug)]
pub struct Message<'a> {
    /// Which of the topics the stream was asked for (its place in that list).
    pub topic: usize,
    /// Receive (log) time, ns since the epoch.
    pub time_ns: u64,
    /// The serialized message.
    pub data: &'a [u8],
    /// The type its connection (bag), channel (MCAP) or topic (db3) declares.
    pub tp: &'a str,
    /// In a ROS 1 bag, the MD5 sum of the definition it was recorded from.
    pub md5: Option<&'a str>,
    /// What a frame made from it should say about its place in the file (read out of time
    /// order because the file cannot be reordered).
    pub warning: Option<String>,
}

/// The messages of some topics, in receive-time order where the container allows it.
pub trait MessageStream {
    /// How many messages the stream holds, if known.
    fn len_hint(&self) -> Option<usize>;
    /// The next message, `Ok(None)` at the end, `Err` (naming the file) when the container
    /// is damaged and nothing after this point can be read.
    fn next_message(&mut self) -> Result<Option<Message<'_>>>;
    /// Positions the stream so that the next message is the `k`-th; false if it cannot.
    fn seek(&mut self, _k: usize) -> bool {
        false
    }
    /// What making the stream found about the file as a whole (its messages out of time
    /// order), taken once, before the first message.
    fn take_warnings(&mut self) -> Vec<String> {
        Vec::new()
    }
}

/// A ROS recording opened for reading.
pub trait Recording {
    /// The file or folder, as messages name it.
    fn label(&self) -> &str;
    /// Which format it is.
    fn format(&self) -> Format;
    /// Whether its messages are ROS 1 serialized (a bag) rather than CDR.
    fn ros1(&self) -> bool;
    /// Every (topic, type) pair it holds, a topic once per type.
    fn topics(&self) -> Vec<(String, String)>;
    /// How many messages `topic` holds, if known without reading them.
    fn count(&self, topic: &str) -> Option<usize>;
    /// What opening it found about the file as a whole (no index, out of order, metadata that
    /// disagrees with the storage), taken once.
    fn take_warnings(&mut self) -> Vec<String>;
    /// Why the file ends early, if opening found it damaged.
    fn damage(&self) -> Option<String> {
        None
    }
    /// Reads the messages of `topics` in file order, handing each to `f` until it breaks: the
    /// passes made when the recording is opened (IMU samples, the sensor's metadata, the first
    /// packets). A damaged container ends the pass with its error.
    fn scan(
        &mut self,
        topics: &[String],
        f: &mut dyn FnMut(Message<'_>) -> ControlFlow<()>,
    ) -> Result<()>;
    /// The messages of `topics`, in receive-time order, as a stream that owns the file.
    fn stream(self: Box<Self>, topics: &[String]) -> Result<Box<dyn MessageStream>>;
}
