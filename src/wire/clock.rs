//! The clock a message is stamped with outside simulated time: the wall clock, as every
//! other ROS 2 node stamps its messages (arrival times of inputs, bag log times).

/// Wall-clock time, ns since the Unix epoch (0 if the system clock is before it).
pub fn now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0)
}
