//! One lock for GPU device lifecycle work in the process: instance, device and pipeline
//! creation, and device destruction, by every backend that drives a Vulkan device (the
//! Vulkan backend through ash, the wgpu backend through wgpu-hal).
//!
//! Why: on NVIDIA's driver (H100 and H200, 580.x), two threads creating Vulkan backends at
//! once hung (the Vulkan backend has serialised its own since); and the conformance suite
//! with cpu, opencl, wgpu and vulkan in parallel test threads still hung in one run of
//! three while wgpu's device and pipeline creation ran beside the Vulkan backend's. The
//! isolation on the H200 (`scripts/gpu-run.sh hang`, `docs/gpu/h200-issue19-hang-isolation.log`):
//! without wgpu, 0 hangs in 3 runs; without vulkan, 0 in 3; without opencl, 1 in 3; all
//! four, 1 in 3. It takes two Vulkan devices in one process, created, compiled for or
//! destroyed from two threads at once. Work on a device (recording, submitting, waiting)
//! is not serialised: each backend owns its queue and uses it from one thread at a time,
//! as Vulkan requires.

use std::cell::Cell;
use std::sync::Mutex;

static LIFECYCLE: Mutex<()> = Mutex::new(());

thread_local! {
    /// Whether this thread holds `LIFECYCLE` (work nested inside lifecycle work, such as
    /// a context dropped while its backend is being created, must not lock it again).
    static HELD: Cell<bool> = const { Cell::new(false) };
}

/// Runs `f` holding the process's device-lifecycle lock (re-entrant on one thread).
pub fn serialised<T>(f: impl FnOnce() -> T) -> T {
    if HELD.with(|c| c.get()) {
        return f();
    }
    let _guard = LIFECYCLE.lock().unwrap_or_else(|e| e.into_inner());
    HELD.with(|c| c.set(true));
    // release the flag even if `f` panics
    struct Reset;
    impl Drop for Reset {
        fn drop(&mut self) {
            HELD.with(|c| c.set(false));
        }
    }
    let _reset = Reset;
    f()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nested_work_does_not_deadlock_and_threads_take_turns() {
        assert_eq!(serialised(|| serialised(|| 7)), 7);
        let inside = std::sync::Arc::new(std::sync::atomic::AtomicU32::new(0));
        let handles: Vec<_> = (0..4)
            .map(|_| {
                let inside = inside.clone();
                std::thread::spawn(move || {
                    serialised(|| {
                        let n = inside.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                        assert_eq!(n, 0, "two threads inside at once");
                        std::thread::sleep(std::time::Duration::from_millis(5));
                        inside.fetch_sub(1, std::sync::atomic::Ordering::SeqCst);
                    })
                })
            })
            .collect();
        for h in handles {
            h.join().unwrap();
        }
    }
}
