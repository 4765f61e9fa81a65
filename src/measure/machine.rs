//! The machine a measurement ran on, for the heading of a report or a benchmark's output.

/// The CPU's model name (the first `model name` line of `/proc/cpuinfo`), or `unknown CPU`
/// where there is none (not Linux, or an architecture that does not give one).
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}
