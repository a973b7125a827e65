//! Time alignment of asynchronous topics (MCAP and ULog): every message of the time-base
//! topic makes one sample; each other mapped topic gives its values at that time, taken
//! from a message at exactly that time or linearly interpolated between the two messages
//! around it when they are at most `gap` seconds apart and no logger dropout lies between
//! them. Otherwise the sample is not aligned (the reader drops and counts it, never
//! bridging the hole). A base message after a dropout starts a new segment.
//!
//! Memory is bounded: a topic's queue holds the messages read ahead of the base time,
//! and a base message waits only until every topic has a message at or after it, or
//! messages more than `gap` later have been read, or the file ended.
//!
//! The mapping's side of topics is here too: a topic's own time field
//! ([`topic_time`]) and the instance of a ULog topic or DataFlash message key `name[k]`
//! ([`split_instance`]).

use std::collections::VecDeque;

use super::error::{ErrorKind, IoError, Location, field, key};
use super::field_path::FieldPathError;
use super::mapping::Mapping;
use super::row_source::RowSource;
use super::summary::Dropout;
use super::units::{Dimension, unit_for};
use super::validate::{MIN_SAMPLE_RATE, QUATERNION_NORM_TOLERANCE};

/// A source of topic messages aligned by an [`Aligner`] (MCAP, ULog): a [`RowSource`]
/// whose rows are the aligned samples.
pub trait TopicSource {
    /// The name of the largest interpolated step in messages, and what else can leave a
    /// sample unaligned (words appended to the message).
    const GAP_WORDS: (&'static str, &'static str);
    /// The aligner the source pushes its messages into.
    fn aligner(&mut self) -> &mut Aligner;
    /// Reads messages until one of a mapped topic was pushed: false at the end of the file.
    fn read_message(&mut self) -> Result<bool, IoError>;
    /// At the end of the file: the error naming a mapped topic that gave no message.
    fn missing_topic(&self) -> Option<IoError>;
    /// Logger dropouts read so far.
    fn dropouts(&self) -> &[Dropout] {
        &[]
    }
    /// The message the end of the file cut short, once reached ([`RowSource::cut_off`]).
    fn cut_off(&self) -> Option<&str> {
        None
    }
    /// Bytes of the file read so far ([`RowSource::bytes_read`]).
    fn bytes_read(&self) -> u64;
}

impl<S: TopicSource> RowSource for S {
    fn next_row(&mut self, raw: &mut [f64]) -> Result<Option<(Location, Option<f64>)>, IoError> {
        while !self.aligner().ready() {
            if !self.read_message()? {
                self.aligner().finish();
                if let Some(e) = self.missing_topic() {
                    return Err(e);
                }
            }
        }
        let align = self.aligner();
        match align.next(raw) {
            None => Ok(None),
            Some(Ok((loc, t))) => Ok(Some((loc, Some(t)))),
            Some(Err(u)) => {
                let (name, also) = S::GAP_WORDS;
                Err(IoError::new(
                    &align.file,
                    u.loc,
                    field(&align.queues[u.topic].key),
                    ErrorKind::NotAligned(format!(
                        "no messages within {name} = {} s around t = {} s{also}",
                        align.gap, u.t
                    )),
                ))
            }
        }
    }

    fn take_segment_break(&mut self) -> bool {
        self.aligner().take_segment_break()
    }

    fn dropouts(&self) -> &[Dropout] {
        TopicSource::dropouts(self)
    }

    fn cut_off(&self) -> Option<&str> {
        TopicSource::cut_off(self)
    }

    fn slow_rotor_speeds(&mut self) -> Option<String> {
        self.aligner().slow_rotor_speeds()
    }

    fn bytes_read(&self) -> u64 {
        TopicSource::bytes_read(self)
    }
}

/// The index of the time-base topic among the mapped topics `keys` of `file`: the
/// mapping's `[mcap] time_base`, else the topic of the body rates.
pub fn base_topic<'a>(
    mapping: &Mapping,
    keys: impl IntoIterator<Item = &'a str>,
    file: &str,
) -> Result<usize, IoError> {
    let base_name = mapping
        .mcap
        .time_base
        .clone()
        .or_else(|| mapping.signals.rates.as_ref().and_then(|r| r.topic.clone()))
        .unwrap_or_default();
    keys.into_iter()
        .position(|k| k == base_name)
        .ok_or_else(|| {
            IoError::new(
                file,
                Location::File,
                key("mcap.time_base"),
                ErrorKind::Mapping(format!("time base topic {base_name:?} maps no signal")),
            )
        })
}

/// The time field of topic `topic` named in the mapping's `[mcap.topic_time]`, parsed
/// by the format's `parse_path`, and its factor to seconds; `None` when the table does
/// not name the topic.
pub fn topic_time<T>(
    mapping: &Mapping,
    topic: &str,
    file: &str,
    parse_path: impl Fn(&str) -> Result<T, FieldPathError>,
) -> Result<Option<(T, f64)>, IoError> {
    let Some(tt) = mapping.mcap.topic_time.get(topic) else {
        return Ok(None);
    };
    let bad = |m: String| {
        IoError::new(
            file,
            Location::File,
            key(&format!("mcap.topic_time.{topic}")),
            ErrorKind::Mapping(m),
        )
    };
    let path = parse_path(&tt.field).map_err(|e| bad(e.to_string()))?;
    let factor = match &tt.unit {
        Some(u) => {
            unit_for(u, None, Dimension::Time, "time")
                .map_err(|e| bad(e.to_string()))?
                .to_si
        }
        None => 1.0,
    };
    Ok(Some((path, factor)))
}

/// A mapped topic key `name[k]` whose instance `k` is not a number 0..=255.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{what} {key:?}: instance {instance:?} is not a number 0..=255")]
pub struct InstanceError {
    /// What the key names: `topic` (ULog) or `message` (DataFlash).
    pub what: &'static str,
    /// The key as written in the mapping.
    pub key: String,
    /// The text between the brackets.
    pub instance: String,
}

/// Splits a mapped key `name[k]` into the name and the instance `k` (0 when absent);
/// `what` is what the key names, for the error.
pub fn split_instance<'k>(
    key: &'k str,
    what: &'static str,
) -> Result<(&'k str, u8), InstanceError> {
    match key.strip_suffix(']').and_then(|t| t.rsplit_once('[')) {
        Some((name, k)) => k
            .parse::<u8>()
            .map(|k| (name, k))
            .map_err(|_| InstanceError {
                what,
                key: key.to_string(),
                instance: k.to_string(),
            }),
        None => Ok((key, 0)),
    }
}

/// One decoded message of a mapped topic, waiting for alignment.
#[derive(Debug, Clone, PartialEq)]
pub struct Message {
    /// Time, s.
    pub t: f64,
    /// Values of the topic's mapped fields, in the order of its slots.
    pub values: Vec<f64>,
    /// Where the message is in the file.
    pub loc: Location,
    /// Logger dropouts before it: messages of different epochs are never interpolated
    /// between.
    pub epoch: u32,
}

/// A base sample a topic could not be aligned to: no message at time `t` (s) and none
/// close enough around it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unaligned {
    /// Index of the topic.
    pub topic: usize,
    /// The base time, s.
    pub t: f64,
    /// Where the base message is in the file.
    pub loc: Location,
}

/// One mapped topic: its key, its slots and its messages not consumed yet.
#[derive(Debug)]
struct Queue {
    /// The topic as the mapping names it.
    key: String,
    slots: Vec<usize>,
    messages: VecDeque<Message>,
    /// Where among `slots` (and a message's values) the attitude quaternion's w, x, y, z
    /// are, when this topic carries it ([`Aligner::with_quaternion`]).
    quaternion: Option<[usize; 4]>,
    /// Messages pushed, and the times of the first and the last (finite), s: the
    /// topic's message rate.
    pushed: u64,
    times: Option<(f64, f64)>,
}

impl Queue {
    /// Mean message rate, Hz (`None` with fewer than two messages apart in time).
    fn rate(&self) -> Option<f64> {
        let (first, last) = self.times?;
        (last > first && self.pushed > 1).then(|| (self.pushed - 1) as f64 / (last - first))
    }
}

/// Aligns the topics' messages on the time-base topic; see the module docs.
#[derive(Debug)]
pub struct Aligner {
    /// File name for messages.
    file: String,
    queues: Vec<Queue>,
    base: usize,
    gap: f64,
    /// Latest finite message time pushed, s (−∞ before any).
    latest: f64,
    /// The topic of the rotor speeds ([`Aligner::with_rotor_speeds`]).
    rotor_topic: Option<usize>,
    last_base_epoch: Option<u32>,
    segment_break: bool,
    eof: bool,
}

impl Aligner {
    /// The aligner of `file`'s topics: topic `j`, named `topics[j].0` in the mapping,
    /// fills the slots `topics[j].1`; topic `base` is the time base; messages at most
    /// `gap` seconds apart are interpolated between.
    pub fn new(file: &str, topics: Vec<(String, Vec<usize>)>, base: usize, gap: f64) -> Self {
        Self {
            file: file.to_string(),
            queues: topics
                .into_iter()
                .map(|(key, slots)| Queue {
                    key,
                    slots,
                    messages: VecDeque::new(),
                    quaternion: None,
                    pushed: 0,
                    times: None,
                })
                .collect(),
            base,
            gap,
            latest: f64::NEG_INFINITY,
            rotor_topic: None,
            last_base_epoch: None,
            segment_break: false,
            eof: false,
        }
    }

    /// Marks the slots `first..first + 4` (`None`: none) as the attitude quaternion
    /// (w, x, y, z): a topic that carries all four interpolates them as one rotation
    /// ([`interpolate_quaternion`]) instead of component by component, whose norm falls
    /// below 1 between messages of a turning vehicle (cos 10° = 0.985 halfway between
    /// messages 40° apart) and vanishes between q and −q, the same attitude.
    pub fn with_quaternion(mut self, first: Option<usize>) -> Self {
        let Some(first) = first else { return self };
        for queue in &mut self.queues {
            let at = |k: usize| queue.slots.iter().position(|&s| s == first + k);
            if let (Some(w), Some(x), Some(y), Some(z)) = (at(0), at(1), at(2), at(3)) {
                queue.quaternion = Some([w, x, y, z]);
            }
        }
        self
    }

    /// Marks the topic that fills slot `first` (`None`: none), the first rotor speed, as
    /// the rotor speeds' ([`Aligner::slow_rotor_speeds`]).
    pub fn with_rotor_speeds(mut self, first: Option<usize>) -> Self {
        self.rotor_topic =
            first.and_then(|first| self.queues.iter().position(|q| q.slots.contains(&first)));
        self
    }

    /// A note when the rotor speeds come from a topic other than the time base, slower
    /// than [`MIN_SAMPLE_RATE`] and than half the base's rate (PX4 logs `esc_status` at
    /// 4 Hz by default): interpolated onto the base, their fast changes are lost; it
    /// says what to log next time. Rates are mean message rates over the messages read.
    pub fn slow_rotor_speeds(&self) -> Option<String> {
        let topic = self.rotor_topic.filter(|&t| t != self.base)?;
        let (rate, base) = (self.queues[topic].rate()?, self.queues[self.base].rate()?);
        if rate >= MIN_SAMPLE_RATE || 2.0 * rate > base {
            return None;
        }
        Some(format!(
            "rotor speeds come from {} at {rate:.1} Hz, interpolated onto the time base at \
             {base:.0} Hz: their changes faster than about {:.1} Hz are lost; log them faster \
             next time (PX4: SDLOG_PROFILE bit 4, high rate, logs esc_status at 200 Hz \
             instead of 4 Hz; ArduPilot: ESC telemetry with SERVO_BLH_TRATE >= 50 Hz or \
             bidirectional DShot, SERVO_BLH_BDMASK; RCOU is logged at 10 Hz)",
            self.queues[topic].key,
            rate / 2.0
        ))
    }

    /// Largest time step interpolated over, s.
    pub fn gap(&self) -> f64 {
        self.gap
    }

    /// Latest finite message time pushed, s (−∞ before any).
    pub fn latest_time(&self) -> f64 {
        self.latest
    }

    /// Queues a message of topic `topic`.
    pub fn push(&mut self, topic: usize, message: Message) {
        if message.t.is_finite() {
            self.latest = self.latest.max(message.t);
            let queue = &mut self.queues[topic];
            queue.pushed += 1;
            queue.times = Some(match queue.times {
                None => (message.t, message.t),
                Some((first, last)) => (first.min(message.t), last.max(message.t)),
            });
        }
        self.queues[topic].messages.push_back(message);
    }

    /// The file has no more messages.
    pub fn finish(&mut self) {
        self.eof = true;
    }

    /// True when the next base message can be aligned (or the file ended); otherwise
    /// more messages must be read.
    pub fn ready(&self) -> bool {
        match self.queues[self.base].messages.front() {
            Some(m) => {
                let tb = m.t;
                (0..self.queues.len()).all(|j| j == self.base || self.settled(j, tb))
            }
            None => self.eof,
        }
    }

    /// True when topic `j` can no longer get a message that brackets base time `tb`.
    fn settled(&self, j: usize, tb: f64) -> bool {
        self.eof
            || self.queues[j].messages.back().is_some_and(|m| m.t >= tb)
            || self.latest > tb + self.gap
    }

    /// Aligns the next base message into `raw` (call when [`Aligner::ready`]): its
    /// location and time (s); `None` when no base message is left.
    pub fn next(&mut self, raw: &mut [f64]) -> Option<Result<(Location, f64), Unaligned>> {
        let base = self.queues[self.base].messages.pop_front()?;
        if self.last_base_epoch.is_some_and(|e| e != base.epoch) {
            self.segment_break = true;
        }
        self.last_base_epoch = Some(base.epoch);
        for (slot, v) in self.queues[self.base].slots.iter().zip(&base.values) {
            raw[*slot] = *v;
        }
        let tb = base.t;
        for (j, queue) in self.queues.iter_mut().enumerate() {
            if j == self.base {
                continue;
            }
            let q = &mut queue.messages;
            while q.len() >= 2 && q[1].t <= tb {
                q.pop_front();
            }
            let slots = queue.slots.iter().copied();
            let aligned = match (q.front(), q.get(1)) {
                (Some(a), _) if a.t == tb => {
                    for (s, v) in slots.zip(&a.values) {
                        raw[s] = *v;
                    }
                    true
                }
                (Some(a), Some(b))
                    if a.t < tb && b.t > tb && b.t - a.t <= self.gap && a.epoch == b.epoch =>
                {
                    let w = (tb - a.t) / (b.t - a.t);
                    for (s, (x, y)) in slots.zip(a.values.iter().zip(&b.values)) {
                        raw[s] = x + w * (y - x);
                    }
                    if let Some(at) = queue.quaternion {
                        let of = |m: &Message| at.map(|k| m.values[k]);
                        if let Some(q) = interpolate_quaternion(of(a), of(b), w) {
                            for (k, v) in at.into_iter().zip(q) {
                                raw[queue.slots[k]] = v;
                            }
                        }
                    }
                    true
                }
                _ => false,
            };
            if !aligned {
                return Some(Err(Unaligned {
                    topic: j,
                    t: tb,
                    loc: base.loc,
                }));
            }
        }
        Some(Ok((base.loc, tb)))
    }

    /// True (once) when the base message returned last follows a logger dropout.
    pub fn take_segment_break(&mut self) -> bool {
        std::mem::take(&mut self.segment_break)
    }
}

/// The attitude a fraction `w` of the way from quaternion `a` to `b` (w, x, y, z): on
/// the shorter arc (`b` taken as −`b` when they lie in opposite hemispheres, the same
/// rotation) and normalised; close to the spherical interpolation for the small steps
/// between messages (within 0.1° for 40° steps). `None` unless both are unit
/// quaternions to [`QUATERNION_NORM_TOLERANCE`]: the component-wise interpolation then
/// stands, for the reader's norm check to judge.
pub fn interpolate_quaternion(a: [f64; 4], b: [f64; 4], w: f64) -> Option<[f64; 4]> {
    let norm = |q: [f64; 4]| q.iter().map(|c| c * c).sum::<f64>().sqrt();
    let unit = |q: [f64; 4]| (norm(q) - 1.0).abs() <= QUATERNION_NORM_TOLERANCE;
    if !(unit(a) && unit(b)) {
        return None;
    }
    let dot: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
    let side = if dot < 0.0 { -1.0 } else { 1.0 };
    let q: [f64; 4] = std::array::from_fn(|k| a[k] + w * (side * b[k] - a[k]));
    let n = norm(q);
    Some(q.map(|c| c / n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instances_split_from_keys() {
        assert_eq!(
            split_instance("actuator_outputs[1]", "topic"),
            Ok(("actuator_outputs", 1))
        );
        assert_eq!(split_instance("a", "topic"), Ok(("a", 0)));
        let e = split_instance("ESC[x]", "message").unwrap_err();
        assert_eq!(
            e.to_string(),
            "message \"ESC[x]\": instance \"x\" is not a number 0..=255"
        );
    }

    fn message(t: f64, value: f64, epoch: u32) -> Message {
        Message {
            t,
            values: vec![value],
            loc: Location::Record(0),
            epoch,
        }
    }

    /// Rotor speeds at 4 Hz (PX4's default esc_status) against a 250 Hz base get the
    /// note naming the topic, both rates and what to log; at 100 Hz, or on the base
    /// itself, none.
    #[test]
    fn slow_rotor_speeds_are_noted_against_the_base_rate() {
        let note = |rotor_hz: f64, rotor_slot: usize| {
            let topics = vec![("base".into(), vec![0]), ("esc_status".into(), vec![1])];
            let mut a = Aligner::new("f", topics, 0, 0.3).with_rotor_speeds(Some(rotor_slot));
            for k in 0..=500 {
                a.push(0, message(k as f64 / 250.0, 0.0, 0));
            }
            for k in 0..=(2.0 * rotor_hz) as usize {
                a.push(1, message(k as f64 / rotor_hz, 0.0, 0));
            }
            a.slow_rotor_speeds()
        };
        let slow = note(4.0, 1).expect("4 Hz is noted");
        assert!(
            slow.starts_with("rotor speeds come from esc_status at 4.0 Hz, interpolated onto the time base at 250 Hz: their changes faster than about 2.0 Hz are lost")
                && slow.contains("SDLOG_PROFILE bit 4"),
            "{slow}"
        );
        assert_eq!(note(100.0, 1), None);
        assert_eq!(note(4.0, 0), None, "on the base");
    }

    /// A yaw of 40° between two attitude messages (a 400 °/s turn logged at 10 Hz): the
    /// base sample a quarter of the way is the attitude at 10° ± 0.1° (nlerp against
    /// slerp) with a unit norm, where the component-wise interpolation has norm 0.989
    /// (0.985 halfway, beyond the reader's 0.01); the same when the later message holds
    /// −q (the same attitude); slots of another topic and non-unit ends are left alone.
    #[test]
    fn an_attitude_quaternion_is_interpolated_as_a_rotation() {
        let yaw = |deg: f64| {
            let h = deg.to_radians() / 2.0;
            vec![h.cos(), 0.0, 0.0, h.sin()]
        };
        for side in [1.0, -1.0] {
            // Slot 0 the base's value, slots 1..5 the quaternion (stored z, w, x, y
            // in the topic's field order), slot 5 another field of its topic.
            let slots = vec![4, 1, 2, 3, 5];
            let mut a = Aligner::new(
                "f",
                vec![("b".into(), vec![0]), ("q".into(), slots)],
                0,
                0.3,
            )
            .with_quaternion(Some(1));
            let stored = |q: Vec<f64>, extra: f64| vec![q[3], q[0], q[1], q[2], extra];
            for t in [0.0, 0.025, 0.1] {
                a.push(0, message(t, t, 0));
            }
            let later: Vec<f64> = yaw(40.0).iter().map(|c| side * c).collect();
            for (t, q, extra) in [(0.0, yaw(0.0), 0.0), (0.1, later, 4.0)] {
                a.push(
                    1,
                    Message {
                        t,
                        values: stored(q, extra),
                        loc: Location::Record(0),
                        epoch: 0,
                    },
                );
            }
            a.finish();
            let mut raw = [0.0; 6];
            a.next(&mut raw).unwrap().unwrap();
            a.next(&mut raw).unwrap().unwrap();
            let q = &raw[1..5];
            let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
            assert!((norm - 1.0).abs() < 1e-15, "{norm}");
            let angle = 2.0 * q[3].atan2(q[0]).to_degrees();
            assert!((angle - 10.0).abs() < 0.1, "side {side}: {angle}°");
            assert!((raw[5] - 1.0).abs() < 1e-15, "the other field is linear");
        }
        let lerp = |w: f64| {
            let (a, b) = (yaw(0.0), yaw(40.0));
            (0..4)
                .map(|k| (a[k] + w * (b[k] - a[k])).powi(2))
                .sum::<f64>()
                .sqrt()
        };
        assert!((lerp(0.25) - 0.989).abs() < 1e-3 && (lerp(0.5) - 0.985).abs() < 1e-3);
        let half = [0.5, 0.0, 0.0, 0.0];
        assert_eq!(
            interpolate_quaternion(half, [1.0, 0.0, 0.0, 0.0], 0.5),
            None
        );
    }

    /// Base at 0.1 s steps, a second topic at 0.25 s steps with value 10 t: exact where
    /// the times meet, linear in between (10 t_b to rounding, 1e-12), refused across a
    /// dropout (epoch 0 → 1).
    #[test]
    fn interpolates_between_bracketing_messages_of_one_epoch() {
        let mut a = Aligner::new(
            "f",
            vec![("b".into(), vec![0]), ("o".into(), vec![1])],
            0,
            0.3,
        );
        for k in 0..6 {
            let t = k as f64 * 0.1;
            a.push(0, message(t, -t, 0));
        }
        a.push(1, message(0.0, 0.0, 0));
        a.push(1, message(0.25, 2.5, 0));
        a.push(1, message(0.5, 5.0, 1));
        a.finish();
        let mut raw = [0.0; 2];
        let mut got = Vec::new();
        while let Some(r) = a.next(&mut raw) {
            got.push(r.map(|(_, t)| (t, raw[0], raw[1])));
        }
        let ok = |t: f64| Ok((t, -t, 10.0 * t));
        assert_eq!(got[0], ok(0.0));
        let (t, base, v) = got[2].unwrap();
        assert_eq!((t, base), (0.2, -0.2));
        assert!((v - 2.0).abs() < 1e-12, "{v}");
        // 0.3 and 0.4 lie between 0.25 (epoch 0) and 0.5 (epoch 1): not aligned.
        for (k, t) in [(3, 0.30000000000000004), (4, 0.4)] {
            assert_eq!(
                got[k],
                Err(Unaligned {
                    topic: 1,
                    t,
                    loc: Location::Record(0)
                })
            );
        }
        assert_eq!(got[5], ok(0.5));
        assert_eq!(got.len(), 6);
    }

    /// A base message waits until the other topic has a message at or after it, or one
    /// more than `gap` later was read; a new epoch on the base topic breaks the segment.
    #[test]
    fn waits_for_bracketing_messages_and_breaks_segments_at_dropouts() {
        let mut a = Aligner::new(
            "f",
            vec![("b".into(), vec![0]), ("o".into(), vec![1])],
            0,
            0.3,
        );
        assert!(!a.ready());
        a.push(0, message(1.0, 1.0, 0));
        assert!(!a.ready());
        a.push(1, message(0.9, 9.0, 0));
        assert!(!a.ready());
        a.push(0, message(1.31, 1.31, 0));
        assert!(a.ready(), "a message more than 0.3 s after 1.0 s was read");
        a.push(1, message(1.2, 12.0, 0));
        let mut raw = [0.0; 2];
        assert!(a.next(&mut raw).unwrap().is_ok());
        assert!((raw[1] - 10.0).abs() < 1e-12);
        assert!(!a.take_segment_break());
        a.push(0, message(1.5, 1.5, 1));
        a.push(1, message(1.5, 15.0, 1));
        assert!(
            a.next(&mut raw).unwrap().is_err(),
            "1.2 s and 1.5 s lie across a dropout"
        );
        assert!(!a.take_segment_break());
        assert_eq!(a.next(&mut raw), Some(Ok((Location::Record(0), 1.5))));
        assert!(a.take_segment_break() && !a.take_segment_break());
        assert_eq!(a.latest_time(), 1.5);
        a.finish();
        assert!(a.ready() && a.next(&mut raw).is_none());
    }
}
