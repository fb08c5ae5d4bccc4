//! Command slots: work submitted without waiting keeps what it uses alive until its fence signals.

mod common;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use ash::vk;
use gpu_allocator::MemoryLocation;
use sensorlight::vk::{Access, Buffer, CommandSlot, barrier};

/// Sets its flag when dropped.
struct Flag(Arc<AtomicBool>);

impl Drop for Flag {
    fn drop(&mut self) {
        self.0.store(true, Ordering::SeqCst);
    }
}

#[test]
fn retired_objects_live_until_the_slot_completes() {
    common::gpu(|device| {
        let mut slot = CommandSlot::new(device).unwrap();
        let usage = vk::BufferUsageFlags::TRANSFER_DST;
        let buffer = Buffer::new(device, "scratch", 1 << 20, usage, MemoryLocation::GpuToCpu).unwrap();
        slot.record(|enc| {
            enc.fill(&buffer, 0x3f80_0000);
            barrier::global(enc, &[Access::TransferWrite], &[Access::HostRead]);
            Ok(())
        })
        .unwrap();
        slot.submit().unwrap();
        // The buffer is handed to the slot while its fill may still run: destroying it now would be a
        // validation error; retired, it goes only once the slot's work is done.
        let dropped = Arc::new(AtomicBool::new(false));
        slot.retire(buffer);
        slot.retire(Flag(dropped.clone()));
        assert!(slot.is_pending() && !dropped.load(Ordering::SeqCst), "dropped before the slot was waited on");
        slot.wait().unwrap();
        assert!(!slot.is_pending() && dropped.load(Ordering::SeqCst), "not dropped once the slot completed");
        // A slot dropped with work in flight waits for it first.
        let target = Buffer::new(device, "target", 1 << 20, usage, MemoryLocation::GpuOnly).unwrap();
        slot.record(|enc| {
            enc.fill(&target, 1);
            Ok(())
        })
        .unwrap();
        slot.submit().unwrap();
        slot.retire(target);
        drop(slot);
    });
}
