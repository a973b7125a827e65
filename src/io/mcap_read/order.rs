//! The order messages are read in: log-time order through the summary's chunk indexes
//! when the file has them, else file order with the streaming linear reader (see the
//! module docs of the MCAP source).

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};

use mcap::records::Record;
use mcap::sans_io::indexed_reader::{IndexedReadEvent, IndexedReader};
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use mcap::sans_io::summary_reader::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};

use super::super::error::{ErrorKind, IoError, Location};
use super::{MAX_RECORD_BYTES, McapSource, Topic};

/// How messages are read: log-time order through chunk indexes, or file order.
pub(super) enum Order {
    /// Through the summary's chunk indexes; `buffer` holds one compressed chunk.
    LogTime {
        reader: Box<IndexedReader>,
        buffer: Vec<u8>,
    },
    /// Record by record in file order (no summary or no chunk index).
    File(Box<LinearReader>),
}

/// The file's summary (channels, schemas, chunk indexes) when it has one that is
/// readable, has chunk indexes and names every topic in `topics`; `None` otherwise (read
/// in file order then). The file position is left at the start; an error is the file's
/// size or the return to the start failing.
pub(super) fn indexed_summary(
    handle: &mut File,
    topics: &[Topic],
) -> Result<Option<mcap::Summary>, std::io::Error> {
    let size = handle.metadata()?.len();
    let mut reader = SummaryReader::new_with_options(
        SummaryReaderOptions::default()
            .with_file_size(size)
            .with_record_length_limit(MAX_RECORD_BYTES),
    );
    let mut readable = true;
    while let Some(event) = reader.next_event() {
        let done = match event {
            Ok(SummaryReadEvent::ReadRequest(need)) => match handle.read(reader.insert(need)) {
                Ok(n) => {
                    reader.notify_read(n);
                    false
                }
                Err(_) => true,
            },
            Ok(SummaryReadEvent::SeekRequest(to)) => match handle.seek(to) {
                Ok(pos) => {
                    reader.notify_seeked(pos);
                    false
                }
                Err(_) => true,
            },
            // A damaged summary: the file-order reader reports what is wrong.
            Err(_) => true,
        };
        if done {
            readable = false;
            break;
        }
    }
    handle.seek(SeekFrom::Start(0))?;
    let summary = if readable { reader.finish() } else { None };
    Ok(summary.filter(|s| {
        !s.chunk_indexes.is_empty()
            && topics
                .iter()
                .all(|t| s.channels.values().any(|c| c.topic == t.name))
    }))
}

/// Why the start of an indexed file is not that of an MCAP file.
#[derive(Debug, thiserror::Error)]
pub(super) enum StartError {
    /// The magic or header record is malformed.
    #[error("MCAP: {0}")]
    Mcap(#[from] mcap::McapError),
    /// The file could not be read.
    #[error(transparent)]
    Read(#[from] std::io::Error),
}

/// Checks the start of the file (magic and header record) with the linear reader, as a
/// file-order read would: reading through the index skips it.
pub(super) fn check_start(handle: &mut File) -> Result<(), StartError> {
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default().with_record_length_limit(MAX_RECORD_BYTES),
    );
    let result = loop {
        match reader.next_event() {
            None => break Ok(()),
            Some(Err(e)) => break Err(e.into()),
            Some(Ok(LinearReadEvent::Record { .. })) => break Ok(()),
            Some(Ok(LinearReadEvent::ReadRequest(need))) => {
                match handle.read(reader.insert(need)) {
                    Ok(n) => reader.notify_read(n),
                    Err(e) => break Err(e.into()),
                }
            }
        }
    };
    handle.seek(SeekFrom::Start(0))?;
    result
}

impl McapSource {
    fn read_error(&self, e: std::io::Error) -> IoError {
        self.err(Location::File, None, ErrorKind::Read(e.to_string()))
    }

    /// The next mapped message in log-time order, through the chunk indexes.
    pub(super) fn read_indexed(&mut self) -> Result<bool, IoError> {
        loop {
            let Order::LogTime { reader, buffer } = &mut self.order else {
                return Ok(false);
            };
            let (header, data) = match reader.next_event() {
                None => return Ok(false),
                Some(Err(e)) => {
                    let index = self.message_index;
                    return Err(self.err(
                        Location::Record(index),
                        None,
                        ErrorKind::Format(format!("MCAP: {e}")),
                    ));
                }
                Some(Ok(IndexedReadEvent::Message { header, data })) => (header, data.to_vec()),
                Some(Ok(IndexedReadEvent::ReadChunkRequest { offset, length })) => {
                    buffer.resize(length, 0);
                    let read = self
                        .handle
                        .seek(SeekFrom::Start(offset))
                        .and_then(|_| self.handle.read_exact(buffer));
                    if let Err(e) = read {
                        return Err(self.read_error(e));
                    }
                    self.bytes_read += length as u64;
                    if let Err(e) = reader.insert_chunk_record_data(offset, buffer) {
                        let index = self.message_index;
                        return Err(self.err(
                            Location::Record(index),
                            None,
                            ErrorKind::Format(format!("MCAP chunk at byte {offset}: {e}")),
                        ));
                    }
                    continue;
                }
            };
            if self.on_message(&header, &data)? {
                return Ok(true);
            }
        }
    }

    /// The next mapped message in file order.
    pub(super) fn read_linear(&mut self) -> Result<bool, IoError> {
        loop {
            let Order::File(reader) = &mut self.order else {
                return Ok(false);
            };
            let event = match reader.next_event() {
                None => return Ok(false),
                Some(Err(e)) => {
                    let index = self.message_index;
                    // A file that ends before its first message (the magic bytes alone,
                    // a cut header) has no message to name: the byte it ends at is.
                    let ended = self.handle.stream_position().ok().filter(|&at| {
                        index == 0 && self.handle.metadata().is_ok_and(|m| m.len() == at)
                    });
                    return Err(match ended {
                        Some(at) => self.err(
                            Location::Offset(at),
                            None,
                            ErrorKind::Format(format!(
                                "MCAP: {e}: the file ends at byte {at}, before any message"
                            )),
                        ),
                        None => self.err(
                            Location::Record(index),
                            None,
                            ErrorKind::Format(format!("MCAP: {e}")),
                        ),
                    });
                }
                Some(Ok(ev)) => ev,
            };
            let (opcode, data) = match event {
                LinearReadEvent::ReadRequest(need) => {
                    match self.handle.read(reader.insert(need)) {
                        Ok(n) => {
                            reader.notify_read(n);
                            self.bytes_read += n as u64;
                        }
                        Err(e) => return Err(self.read_error(e)),
                    }
                    continue;
                }
                LinearReadEvent::Record { opcode, data } => (opcode, data.to_vec()),
            };
            let record = mcap::parse_record(opcode, &data).map_err(|e| {
                IoError::new(
                    &self.file,
                    Location::Record(self.message_index),
                    None,
                    ErrorKind::Format(format!("MCAP record: {e}")),
                )
            })?;
            match record {
                Record::Schema { header, data } => {
                    self.schemas
                        .insert(header.id, (header.name, header.encoding, data.into_owned()));
                }
                Record::Channel(ch) => {
                    self.add_channel(ch.id, &ch.topic, &ch.message_encoding, ch.schema_id)?;
                }
                Record::Message { header, data } if self.on_message(&header, &data)? => {
                    return Ok(true);
                }
                _ => {}
            }
        }
    }
}
