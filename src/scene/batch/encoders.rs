//! The batch's encoders: images rendered by the render thread are encoded and written by several
//! threads at once, and handed on to the writer in job order.
//!
//! On a GPU the render thread outruns one encoder: an NVIDIA H200 rendered the 512² bench image
//! in 7.6 ms of GPU time, while the batch with one encoder (the display transform, deflate, the
//! file) finished an image every 29 ms (BENCHMARKS.md, "NVIDIA H200"). So up to [`MAX_ENCODERS`] threads encode, as many as the
//! machine has cores beside the render and writer threads (one on a 2-core machine, where the
//! GPU is lavapipe on those cores and nothing is gained). The images they hold are bounded in
//! bytes ([`InFlight`]), not in count, so that a batch of 8K images does not hold gigabytes.
//!
//! Jobs between the render thread and the writer are also bounded in count ([`Unwritten`]): a
//! failed job carries no image, so the byte bound let a batch of failing jobs run thousands of
//! jobs ahead of a slow writer, and the first Ctrl-C (which stops only the render thread) waited
//! for all of them.

use std::collections::BTreeMap;
use std::sync::{mpsc, Condvar, Mutex};

use super::manifest::ManifestRow;
use super::run::{thumbnail_from_file, write_image, Message};
use super::sheet::Thumbnail;
use super::sink::OutputSink;
use crate::Result;

/// The most encoder threads a batch runs.
pub const MAX_ENCODERS: usize = 8;

/// Bytes of rendered images (linear RGBA32F) the encoders may hold at once; one image is always
/// let through, however large.
pub const IN_FLIGHT_BYTES: u64 = 512 << 20;

/// Jobs the render thread may be ahead of the writer (sent, not yet in the manifest): enough to
/// keep [`MAX_ENCODERS`] encoders and the queues busy, few enough that the writer finishes them
/// in milliseconds after a Ctrl-C.
pub const MAX_UNWRITTEN: usize = 64;

/// Encoder threads for this machine: its cores less the render and writer threads, 1 to
/// [`MAX_ENCODERS`].
pub fn encoder_count() -> usize {
    std::thread::available_parallelism()
        .map_or(1, |n| n.get().saturating_sub(2))
        .clamp(1, MAX_ENCODERS)
}

/// A message with its image encoded and written (or its failure) and its tile made.
pub(super) enum Written {
    Rendered {
        row: ManifestRow,
        /// The tile (if the contact sheet shows this job), or why the file could not be written.
        result: Result<Option<Thumbnail>>,
    },
    /// A job whose output was already there (its tile read back from the file, if it can be).
    Skipped {
        row: ManifestRow,
        thumbnail: Option<Thumbnail>,
    },
    Failed {
        row: ManifestRow,
    },
}

/// The bytes of rendered images between the render thread and the encoders, and how many
/// encoders are still running (with none left nothing would free them: the render thread must
/// not wait then, its next send fails instead).
pub(super) struct InFlight {
    state: Mutex<(u64, usize)>,
    freed: Condvar,
}

impl InFlight {
    pub fn new(encoders: usize) -> Self {
        InFlight {
            state: Mutex::new((0, encoders)),
            freed: Condvar::new(),
        }
    }

    /// Waits until `bytes` more fit in [`IN_FLIGHT_BYTES`] (or nothing is held, or no encoder is
    /// left), then holds them.
    pub fn acquire(&self, bytes: u64) {
        let mut state = self.state.lock().unwrap_or_else(|p| p.into_inner());
        while state.0 > 0 && state.0 + bytes > IN_FLIGHT_BYTES && state.1 > 0 {
            state = self.freed.wait(state).unwrap_or_else(|p| p.into_inner());
        }
        state.0 += bytes;
    }

    pub fn release(&self, bytes: u64) {
        let mut state = self.state.lock().unwrap_or_else(|p| p.into_inner());
        state.0 = state.0.saturating_sub(bytes);
        self.freed.notify_all();
    }

    /// One encoder ended; returns how many are left.
    fn encoder_gone(&self) -> usize {
        let mut state = self.state.lock().unwrap_or_else(|p| p.into_inner());
        state.1 = state.1.saturating_sub(1);
        self.freed.notify_all();
        state.1
    }
}

/// Jobs sent by the render thread and not yet written by the writer, at most [`MAX_UNWRITTEN`];
/// once the writer is gone (closed) nothing waits.
pub(super) struct Unwritten {
    state: Mutex<(usize, bool)>,
    written: Condvar,
}

impl Unwritten {
    pub fn new() -> Self {
        Unwritten {
            state: Mutex::new((0, true)),
            written: Condvar::new(),
        }
    }

    /// Waits until fewer than [`MAX_UNWRITTEN`] jobs are unwritten (or the writer is gone), then
    /// counts one more.
    pub fn acquire(&self) {
        let mut state = self.state.lock().unwrap_or_else(|p| p.into_inner());
        while state.0 >= MAX_UNWRITTEN && state.1 {
            state = self.written.wait(state).unwrap_or_else(|p| p.into_inner());
        }
        state.0 += 1;
    }

    /// One job is written.
    pub fn release(&self) {
        let mut state = self.state.lock().unwrap_or_else(|p| p.into_inner());
        state.0 = state.0.saturating_sub(1);
        self.written.notify_all();
    }

    /// The writer is gone: nothing will be released again.
    pub fn close(&self) {
        let mut state = self.state.lock().unwrap_or_else(|p| p.into_inner());
        state.1 = false;
        self.written.notify_all();
    }
}

/// Closes [`Unwritten`] when the writer ends, however it ends (a panic too).
pub(super) struct Writing<'a>(pub &'a Unwritten);

impl Drop for Writing<'_> {
    fn drop(&mut self) {
        self.0.close();
    }
}

/// Tells [`InFlight`] that its encoder is gone, however it ends (a panic too).
/// The last one also drops the render thread's receiver, so that its next send fails instead of
/// waiting for ever once the queue is full (the writer panicked, or every encoder did).
struct Running<'a> {
    in_flight: &'a InFlight,
    jobs: &'a Jobs,
}

impl Drop for Running<'_> {
    fn drop(&mut self) {
        if self.in_flight.encoder_gone() == 0 {
            *self.jobs.lock().unwrap_or_else(|p| p.into_inner()) = None;
        }
    }
}

/// The render thread's queue as the encoders share it; `None` once the last encoder is gone.
pub(super) type Jobs = Mutex<Option<mpsc::Receiver<(usize, Message)>>>;

/// The bytes a message holds while it waits for an encoder.
pub(super) fn message_bytes(message: &Message) -> u64 {
    match message {
        Message::Render { image, .. } => image.pixels.len() as u64 * 16,
        _ => 0,
    }
}

/// One encoder: takes the next job's message, encodes and writes its image, sends the result
/// (with the job's place in the run) to the writer; ends when the render thread is done or the
/// writer is gone.
pub(super) fn encode_loop(
    jobs: &Jobs,
    done: mpsc::Sender<(usize, Written)>,
    in_flight: &InFlight,
    sink: &dyn OutputSink,
) {
    let _running = Running { in_flight, jobs };
    loop {
        let next = match jobs.lock().unwrap_or_else(|p| p.into_inner()).as_ref() {
            Some(receiver) => receiver.recv().ok(),
            None => None,
        };
        let Some((place, message)) = next else { return };
        let bytes = message_bytes(&message);
        let written = match message {
            Message::Render {
                row,
                path,
                image,
                png,
                tile,
            } => Written::Rendered {
                row,
                result: write_image(sink, &path, &image, &png)
                    .map(|()| tile.then(|| Thumbnail::from_hdr(&image, &png))),
            },
            Message::Skipped { row, path, tile } => Written::Skipped {
                row,
                thumbnail: tile.then(|| thumbnail_from_file(&path)).flatten(),
            },
            Message::Failed { row } => Written::Failed { row },
        };
        in_flight.release(bytes);
        if done.send((place, written)).is_err() {
            return;
        }
    }
}

/// Hands the encoders' results on in job order: `receive` yields them as they finish, `apply`
/// gets them by place 0, 1, 2, …
pub(super) fn in_order(
    receive: impl IntoIterator<Item = (usize, Written)>,
    mut apply: impl FnMut(Written),
) {
    let mut waiting = BTreeMap::new();
    let mut next = 0;
    for (place, written) in receive {
        waiting.insert(place, written);
        while let Some(written) = waiting.remove(&next) {
            apply(written);
            next += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{in_order, InFlight, Unwritten, Written, IN_FLIGHT_BYTES, MAX_UNWRITTEN};
    use crate::scene::batch::manifest::ManifestRow;

    fn failed(job: usize) -> Written {
        Written::Failed {
            row: ManifestRow {
                job,
                values: Vec::new(),
                output: String::new(),
                scene_hash: String::new(),
                status: String::new(),
            },
        }
    }

    /// Results finishing in any order reach the writer by place.
    #[test]
    fn results_are_applied_in_job_order() {
        let finished = [3, 0, 4, 1, 2, 7, 5, 6].map(|place| (place, failed(place)));
        let mut applied = Vec::new();
        in_order(finished, |w| match w {
            Written::Failed { row } => applied.push(row.job),
            _ => unreachable!("only failures were sent"),
        });
        assert_eq!(applied, (0..8).collect::<Vec<_>>());
    }

    /// One image always passes, however large; more wait for room, unless no encoder is left.
    #[test]
    fn in_flight_bytes_are_bounded_but_never_block_without_encoders() {
        let in_flight = InFlight::new(1);
        in_flight.acquire(IN_FLIGHT_BYTES * 3);
        in_flight.release(IN_FLIGHT_BYTES * 3);
        in_flight.acquire(IN_FLIGHT_BYTES / 2);
        in_flight.acquire(IN_FLIGHT_BYTES / 2);
        in_flight.encoder_gone();
        // Over the budget with no encoder left to free it: returns at once.
        in_flight.acquire(IN_FLIGHT_BYTES);
    }

    /// The render thread waits once MAX_UNWRITTEN jobs are unwritten, and goes on when one is
    /// written or the writer is gone.
    #[test]
    fn unwritten_jobs_are_bounded_in_count_until_the_writer_is_gone() {
        let unwritten = std::sync::Arc::new(Unwritten::new());
        for _ in 0..MAX_UNWRITTEN {
            unwritten.acquire();
        }
        let waiting = {
            let unwritten = std::sync::Arc::clone(&unwritten);
            std::thread::spawn(move || {
                unwritten.acquire();
                unwritten.acquire();
            })
        };
        // Long enough for the thread to have passed an acquire that does not wait.
        std::thread::sleep(std::time::Duration::from_millis(50));
        assert!(
            !waiting.is_finished(),
            "a job past the bound was let through"
        );
        unwritten.release();
        std::thread::sleep(std::time::Duration::from_millis(50));
        assert!(
            !waiting.is_finished(),
            "two jobs passed where one was written"
        );
        unwritten.close();
        waiting.join().unwrap();
    }
}
