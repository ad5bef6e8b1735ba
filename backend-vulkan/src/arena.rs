//! Host-visible scratch memory reused by every `execute` (no allocation per kernel): kernel
//! parameters (uniforms) and the staging copies of uploads and writes are bump-allocated
//! from one mapped buffer, which is reset when an execute starts (each execute waits for
//! its work before it returns, so nothing of the last one is still read). A request that
//! does not fit gets its own buffer for this execute, as before, and the arena grows to fit
//! the whole execute's requests at the next reset (up to [`MAX_ARENA_BYTES`]: larger
//! uploads, such as whole scenes, keep their own staging).

use crate::context::Context;
use crate::memory::Buffer;
use ash::vk;
use caustica_core::backend::BackendError;
use std::sync::Arc;

/// Largest arena (bytes): enough for a frame's parameters and its per-frame writes.
pub const MAX_ARENA_BYTES: u64 = 64 << 20;

/// A bump allocator over one host-visible, mapped buffer.
#[derive(Default)]
pub struct Arena {
    buffer: Option<Buffer>,
    size: u64,
    used: u64,
    /// What the last execute asked for in all (the next reset's size).
    wanted: u64,
}

impl Arena {
    /// Starts an execute: grows the buffer to what the last one wanted (within
    /// [`MAX_ARENA_BYTES`]) and empties it.
    pub fn reset(&mut self, ctx: &Arc<Context>) -> Result<(), BackendError> {
        let want = self.wanted.min(MAX_ARENA_BYTES);
        if want > self.size {
            let size = want.next_power_of_two().clamp(64 << 10, MAX_ARENA_BYTES);
            self.buffer = Some(Buffer::new(
                ctx,
                size,
                vk::BufferUsageFlags::UNIFORM_BUFFER
                    | vk::BufferUsageFlags::STORAGE_BUFFER
                    | vk::BufferUsageFlags::TRANSFER_SRC,
                true,
                "host arena (parameters and staging)",
            )?);
            self.size = size;
        }
        self.used = 0;
        self.wanted = 0;
        Ok(())
    }

    /// `data` copied into the arena at an offset aligned to `align`: the buffer and the
    /// offset, or `None` when it does not fit (the caller makes its own buffer; the arena
    /// grows at the next reset).
    pub fn put(&mut self, data: &[u8], align: u64) -> Option<(vk::Buffer, u64)> {
        let len = data.len() as u64;
        if len > MAX_ARENA_BYTES / 4 {
            return None; // a scene upload: its own staging, not a reason to grow
        }
        // an upper bound of this execute's total, for the next reset
        self.wanted += len + align;
        let buffer = self.buffer.as_ref()?;
        let at = self.used.next_multiple_of(align.max(1));
        if at + len > self.size {
            return None;
        }
        buffer.write(at as usize, data);
        self.used = at + len;
        Some((buffer.buffer, at))
    }
}
