//! `auto` keeps the best backend that opens here by device type: hardware GPUs, then the
//! native CPU backend, then GPU APIs emulated on the CPU (lavapipe, PoCL).

use caustica::{auto_order, backend_statuses, open_backend, DeviceType};

#[test]
fn auto_opens_the_first_of_its_order_and_the_order_ranks_device_types() {
    let order = auto_order();
    assert!(
        !order.is_empty(),
        "no backend opens (the cpu backend always should)"
    );
    for w in order.windows(2) {
        assert!(w[0].1.auto_rank() <= w[1].1.auto_rank(), "{order:?}");
    }
    let chosen = open_backend("auto").expect("auto opens something");
    assert_eq!(chosen.name(), order[0].0);
    assert_eq!(chosen.capabilities().device_type, order[0].1);
    // The native CPU backend comes before any software GPU.
    let cpu = order
        .iter()
        .position(|(n, _)| *n == "cpu")
        .expect("cpu opens");
    for (i, (n, t)) in order.iter().enumerate() {
        if *t == DeviceType::SoftwareGpu {
            assert!(
                i > cpu,
                "{n} ({t:?}) ranked before the cpu backend: {order:?}"
            );
        }
    }
}

#[test]
fn every_backend_states_its_device_type() {
    for s in backend_statuses() {
        if let Ok((_, t)) = &s.available {
            assert_ne!(
                *t,
                DeviceType::Other,
                "{} does not say what it runs on",
                s.name
            );
        }
    }
    assert!(DeviceType::Cpu.auto_rank() < DeviceType::SoftwareGpu.auto_rank());
    assert!(DeviceType::DiscreteGpu.auto_rank() < DeviceType::Cpu.auto_rank());
}
