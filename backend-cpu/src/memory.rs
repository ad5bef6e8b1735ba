//! Host buffers: 8-byte aligned byte storage, viewed as typed slices or as `AtomicU64`s;
//! the backend's buffers by resource, read back by copy.

use crate::CpuBackend;
use caustica_core::backend::{check_write, BackendError};
use caustica_core::device::handle::ResourceId;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};

pub(crate) struct Storage {
    words: Vec<u64>,
    bytes: usize,
}

const _: () = assert!(std::mem::align_of::<AtomicU64>() == std::mem::align_of::<u64>());

/// The host memory that CPU backends' buffers may take together: what the system had
/// available (with free swap) when the process's first CPU backend opened, less what the
/// buffers of every CPU backend of the process hold. A buffer is zeroed by the allocator
/// (pages the system fills on first touch), so without this count a frame too large for
/// the host would be killed by the system as its kernels touched the pages, instead of
/// failing with an error when it is made; and since untouched pages still count as
/// available, two backends that each counted only their own buffers against their own
/// reading could together take twice what the host has.
#[derive(Debug)]
pub(crate) struct SharedBudget {
    /// Bytes the system had available; `None` where it does not say (not Linux).
    available: Option<u64>,
    /// Bytes the live buffers of every backend sharing this budget hold.
    held: AtomicU64,
}

impl SharedBudget {
    fn new(available: Option<u64>) -> Arc<SharedBudget> {
        Arc::new(SharedBudget {
            available,
            held: AtomicU64::new(0),
        })
    }
}

/// One backend's share of a [`SharedBudget`]: what its buffers hold, given back when it is
/// dropped.
#[derive(Debug)]
pub(crate) struct HostBudget {
    shared: Arc<SharedBudget>,
    /// Bytes this backend's live buffers hold.
    mine: u64,
}

impl HostBudget {
    /// A share of the process's budget (read from `/proc/meminfo`'s `MemAvailable` plus
    /// `SwapFree` when the first CPU backend opens).
    pub fn now() -> HostBudget {
        static PROCESS: OnceLock<Arc<SharedBudget>> = OnceLock::new();
        let shared = PROCESS.get_or_init(|| {
            SharedBudget::new(
                std::fs::read_to_string("/proc/meminfo")
                    .ok()
                    .and_then(|m| meminfo_available(&m)),
            )
        });
        HostBudget::of(shared.clone())
    }

    fn of(shared: Arc<SharedBudget>) -> HostBudget {
        HostBudget { shared, mine: 0 }
    }

    /// Takes `bytes` for a buffer named `label`, or says why the host cannot hold it.
    pub fn take(&mut self, bytes: u64, label: &str) -> Result<(), BackendError> {
        let held = &self.shared.held;
        let mut now = held.load(Ordering::Relaxed);
        loop {
            let after = now.saturating_add(bytes);
            if let Some(available) = self.shared.available.filter(|&a| after > a) {
                return Err(BackendError::OutOfMemory {
                    bytes,
                    what: format!(
                        "{label} (host memory: the CPU backends' buffers would hold {after} \
                         bytes, {available} were available when the first one opened)"
                    ),
                });
            }
            match held.compare_exchange_weak(now, after, Ordering::Relaxed, Ordering::Relaxed) {
                Ok(_) => break,
                Err(seen) => now = seen,
            }
        }
        self.mine = self.mine.saturating_add(bytes);
        Ok(())
    }

    /// Gives back a freed buffer's bytes.
    pub fn give(&mut self, bytes: u64) {
        let bytes = bytes.min(self.mine);
        self.mine -= bytes;
        self.shared.held.fetch_sub(bytes, Ordering::Relaxed);
    }
}

impl Drop for HostBudget {
    fn drop(&mut self) {
        self.shared.held.fetch_sub(self.mine, Ordering::Relaxed);
    }
}

/// `MemAvailable` plus `SwapFree` of a `/proc/meminfo` text, in bytes.
fn meminfo_available(meminfo: &str) -> Option<u64> {
    let kib = |key: &str| {
        meminfo
            .lines()
            .find_map(|l| l.strip_prefix(key))
            .and_then(|rest| rest.trim().strip_suffix("kB"))
            .and_then(|n| n.trim().parse::<u64>().ok())
    };
    let available = kib("MemAvailable:")?;
    Some((available + kib("SwapFree:").unwrap_or(0)).saturating_mul(1024))
}

impl Storage {
    /// A zero-filled buffer (zeroed by the allocator: its pages are touched when they are
    /// used); allocation failure is a typed out-of-memory error.
    pub fn zeroed(bytes: u64, label: &str) -> Result<Storage, BackendError> {
        let oom = || BackendError::OutOfMemory {
            bytes,
            what: format!("{label} (host memory)"),
        };
        let n = usize::try_from(bytes.div_ceil(8)).map_err(|_| oom())?;
        let words = bytemuck::allocation::try_zeroed_vec::<u64>(n).map_err(|_| oom())?;
        Ok(Storage {
            words,
            bytes: bytes as usize,
        })
    }

    /// The buffer's size in bytes.
    pub fn len(&self) -> u64 {
        self.bytes as u64
    }

    pub fn bytes(&self) -> &[u8] {
        &bytemuck::cast_slice(&self.words)[..self.bytes]
    }

    fn bytes_mut(&mut self) -> &mut [u8] {
        &mut bytemuck::cast_slice_mut(&mut self.words)[..self.bytes]
    }

    pub fn clear(&mut self) {
        self.words.fill(0);
    }

    /// The first `len` elements as `T`.
    pub fn as_slice<T: bytemuck::Pod>(&self, len: u32) -> Result<&[T], BackendError> {
        let need = len as usize * std::mem::size_of::<T>();
        if need > self.bytes {
            return Err(BackendError::BadArgument(format!(
                "buffer of {} bytes read as {need}",
                self.bytes
            )));
        }
        Ok(bytemuck::cast_slice(&self.bytes()[..need]))
    }

    pub fn as_mut_slice<T: bytemuck::Pod>(&mut self, len: u32) -> Result<&mut [T], BackendError> {
        let need = len as usize * std::mem::size_of::<T>();
        if need > self.bytes {
            return Err(BackendError::BadArgument(format!(
                "buffer of {} bytes written as {need}",
                self.bytes
            )));
        }
        Ok(bytemuck::cast_slice_mut(&mut self.bytes_mut()[..need]))
    }

    /// Replaces the whole contents; sizes must match.
    pub fn write_all<T: bytemuck::Pod>(&mut self, data: &[T]) -> Result<(), BackendError> {
        let src: &[u8] = bytemuck::cast_slice(data);
        if src.len() != self.bytes {
            return Err(BackendError::BadArgument(format!(
                "{} bytes written to a buffer of {}",
                src.len(),
                self.bytes
            )));
        }
        self.bytes_mut().copy_from_slice(src);
        Ok(())
    }

    /// Writes `data` from byte `offset` on (`label`'s `Step::Write`).
    pub fn write_at(&mut self, label: &str, offset: u64, data: &[u8]) -> Result<(), BackendError> {
        check_write(label, self.bytes as u64, offset, data.len())?;
        self.bytes_mut()[offset as usize..offset as usize + data.len()].copy_from_slice(data);
        Ok(())
    }

    /// Writes `data` at the start of the buffer.
    pub fn write_prefix<T: bytemuck::Pod>(&mut self, data: &[T]) -> Result<(), BackendError> {
        let src: &[u8] = bytemuck::cast_slice(data);
        if src.len() > self.bytes {
            return Err(BackendError::BadArgument(format!(
                "{} bytes written to a buffer of {}",
                src.len(),
                self.bytes
            )));
        }
        self.bytes_mut()[..src.len()].copy_from_slice(src);
        Ok(())
    }

    /// The first `bytes` bytes as 32-bit atomics (shared access: kernels add
    /// concurrently).
    pub fn as_atomic_u32(&self, bytes: u64) -> Result<&[AtomicU32], BackendError> {
        if bytes as usize > self.bytes || !bytes.is_multiple_of(4) {
            return Err(BackendError::BadArgument("atomic view out of range".into()));
        }
        let words: &[u32] = bytemuck::cast_slice(&self.words[..(bytes as usize).div_ceil(8)]);
        let words = &words[..bytes as usize / 4];
        // SAFETY: AtomicU32 has the size and alignment of u32 (the storage is u64-aligned);
        // the slice is only accessed through atomics while this shared borrow lives, and
        // u32 has no invalid bit patterns.
        Ok(unsafe { &*(words as *const [u32] as *const [AtomicU32]) })
    }

    /// The first `bytes` bytes as atomics (shared access: kernels add concurrently).
    pub fn as_atomic_u64(&self, bytes: u64) -> Result<&[AtomicU64], BackendError> {
        if bytes as usize > self.bytes || !bytes.is_multiple_of(8) {
            return Err(BackendError::BadArgument("atomic view out of range".into()));
        }
        let words = &self.words[..bytes as usize / 8];
        // SAFETY: AtomicU64 has the size and (asserted above) alignment of u64; the slice is
        // only accessed through atomics while this shared borrow lives, and u64 has no
        // invalid bit patterns.
        Ok(unsafe { &*(words as *const [u64] as *const [AtomicU64]) })
    }
}

impl CpuBackend {
    /// Holds `s` as buffer `id` (its bytes taken from [`CpuBackend::host`]); the bytes of
    /// a buffer it replaces are given back.
    pub(crate) fn insert_buffer(&mut self, id: ResourceId, s: Storage) {
        if let Some(old) = self.buffers.insert(id, s) {
            self.host.give(old.len());
        }
    }

    /// Buffer `id`.
    pub(crate) fn get(&self, id: ResourceId) -> Result<&Storage, BackendError> {
        self.buffers.get(id)
    }

    /// Buffer `id`, to write.
    pub(crate) fn get_mut(&mut self, id: ResourceId) -> Result<&mut Storage, BackendError> {
        self.buffers.get_mut(id)
    }

    /// Replaces the whole of buffer `id` with `data` (a kernel's result).
    pub(crate) fn put<T: bytemuck::Pod>(
        &mut self,
        id: ResourceId,
        data: &[T],
    ) -> Result<(), BackendError> {
        self.get_mut(id)?.write_all(data)
    }

    /// [`caustica_core::backend::Backend::read`]'s body.
    pub(crate) fn read_resource(&self, id: ResourceId) -> Result<Vec<u8>, BackendError> {
        let src = self.get(id)?.bytes();
        let mut out = caustica_core::device::host_bytes(src.len() as u64, "reading a buffer back")?;
        out.copy_from_slice(src);
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_budget_reads_meminfo_and_refuses_what_does_not_fit() {
        let m = "MemTotal:       24000000 kB\nMemFree:  100 kB\nMemAvailable:   2000 kB\nSwapTotal: 0 kB\nSwapFree:        48 kB\n";
        assert_eq!(meminfo_available(m), Some(2048 * 1024));
        assert_eq!(meminfo_available("MemTotal: 1 kB\n"), None);
        let shared = SharedBudget::new(Some(1000));
        let mut b = HostBudget::of(shared.clone());
        b.take(600, "a").unwrap();
        let e = b.take(500, "b").unwrap_err().to_string();
        assert!(e.contains("b (host memory") && e.contains("1100"), "{e}");
        b.give(600);
        b.take(1000, "c").unwrap();
        b.give(1000);
        // two backends share it: together they hold at most what was available, and a
        // dropped one gives its bytes back
        let mut other = HostBudget::of(shared.clone());
        b.take(700, "d").unwrap();
        let e = other.take(400, "e").unwrap_err().to_string();
        assert!(e.contains("1100"), "{e}");
        other.take(300, "f").unwrap();
        // a backend gives back no more than it holds
        other.give(5000);
        assert_eq!(shared.held.load(Ordering::Relaxed), 700);
        other.take(300, "g").unwrap();
        drop(b);
        assert_eq!(shared.held.load(Ordering::Relaxed), 300);
        other.take(700, "h").unwrap();
        drop(other);
        assert_eq!(shared.held.load(Ordering::Relaxed), 0);
        // where the system does not say, no limit
        let mut open = HostBudget::of(SharedBudget::new(None));
        open.take(u64::MAX, "i").unwrap();
    }
}
