//! Temporal resources: a pair of device buffers of which one holds the previous frame's
//! history and the other receives this frame's (ping-pong), swapped after each frame.
//! Techniques with history (PhotonGi's temporal accumulation, the shared temporal blend)
//! own one per accumulated quantity.

use crate::device::handle::Buf;
use crate::recording::Recording;

/// Two buffers of `len` elements, read one and write the other, swapped per frame.
#[derive(Clone, Copy, Debug)]
pub struct PingPong<T> {
    buffers: [Buf<T>; 2],
    /// Index of the buffer holding the history (the previous frame's result).
    history: usize,
    /// Frames written so far (0: the history is empty and must not be blended).
    pub frames: u64,
}

impl<T> PingPong<T> {
    /// Records the creation of both (zeroed) buffers.
    pub fn create(rec: &mut Recording, len: u32, label: &'static str) -> PingPong<T> {
        PingPong {
            buffers: [rec.create(len, label), rec.create(len, label)],
            history: 0,
            frames: 0,
        }
    }

    /// The previous frame's result.
    pub fn history(&self) -> Buf<T> {
        self.buffers[self.history]
    }

    /// Where this frame writes.
    pub fn current(&self) -> Buf<T> {
        self.buffers[1 - self.history]
    }

    /// After the frame: this frame's result becomes the history.
    pub fn swap(&mut self) {
        self.history = 1 - self.history;
        self.frames += 1;
    }

    /// Forgets the history (camera cut, scene change): the next frame must not blend.
    pub fn reset(&mut self) {
        self.frames = 0;
    }

    /// Both buffers (to free them).
    pub fn buffers(&self) -> [Buf<T>; 2] {
        self.buffers
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn swap_alternates_history_and_current() {
        let mut rec = Recording::new();
        let mut p: PingPong<f32> = PingPong::create(&mut rec, 4, "history");
        assert_eq!(rec.steps.len(), 2);
        let (h0, c0) = (p.history().id, p.current().id);
        assert_ne!(h0, c0);
        p.swap();
        assert_eq!((p.history().id, p.current().id), (c0, h0));
        assert_eq!(p.frames, 1);
        p.reset();
        assert_eq!(p.frames, 0);
    }
}
