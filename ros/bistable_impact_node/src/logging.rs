//! Where the node's DDS-free logic writes its log lines: the binary's logger (standard error
//! and `/rosout`) implements [`Log`]; tests record the lines.

pub use ros2_client::log::LogLevel;

/// A sink for log lines.
pub trait Log {
    /// Logs `msg` at `level` (the sink may filter by level).
    fn log(&self, level: LogLevel, msg: &str);
}

/// Records every line, for tests.
#[cfg(test)]
#[derive(Default)]
pub(crate) struct Recorder(pub std::cell::RefCell<Vec<(LogLevel, String)>>);

#[cfg(test)]
impl Log for Recorder {
    fn log(&self, level: LogLevel, msg: &str) {
        self.0.borrow_mut().push((level, msg.to_owned()));
    }
}

#[cfg(test)]
impl Recorder {
    /// The lines logged at `level`.
    pub(crate) fn at(&self, level: LogLevel) -> Vec<String> {
        let lines = self.0.borrow();
        lines
            .iter()
            .filter(|(l, _)| *l == level)
            .map(|(_, m)| m.clone())
            .collect()
    }
}
