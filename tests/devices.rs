//! Devices opened and closed on many threads at once, as the test harness itself does: each keeps its own
//! memory, and none crashes in the loader (see `vk::instance::loader_lock`).

mod common;

use std::sync::Barrier;

use ash::vk;
use sensorlight::vk::transfer;

#[test]
fn devices_open_and_close_on_many_threads_at_once() {
    const THREADS: u32 = 8;
    const ROUNDS: u32 = 6;
    let start = Barrier::new(THREADS as usize);
    std::thread::scope(|scope| {
        for thread in 0..THREADS {
            let start = &start;
            scope.spawn(move || {
                start.wait();
                for round in 0..ROUNDS {
                    let data: Vec<u32> = (0..4096).map(|i| i ^ (thread << 24) ^ (round << 16)).collect();
                    let back = common::gpu(|device| {
                        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
                        let buffer = transfer::upload(device, "round trip", &data, usage).unwrap();
                        transfer::read_buffer::<u32>(device, &buffer, data.len()).unwrap()
                    });
                    assert_eq!(back, data, "thread {thread}, round {round}: the device returned other memory");
                }
            });
        }
    });
}
