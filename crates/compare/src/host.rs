//! The machine a run's times come from: times measured on different machines are not
//! comparable, so `results.csv` records the host of every row and a merged report flags rows
//! from more than one host.

use super::output::csv_text;

/// A machine: its CPU model and logical cores.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Host {
    /// The CPU model as the operating system names it (`/proc/cpuinfo`'s `model name` on
    /// Linux), `unknown` where it cannot be read. Never holds a comma, tab or line break (they
    /// become spaces), so it is one CSV field as it is.
    pub cpu: String,
    /// Logical cores the operating system reports (`std::thread::available_parallelism`).
    pub cores: usize,
}

impl Host {
    /// This machine.
    pub fn this() -> Host {
        let cpu = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|text| cpu_model(&text))
            .unwrap_or_else(|| "unknown".to_string());
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        Host {
            cpu: csv_text(&cpu),
            cores,
        }
    }

    /// `cpu (N cores)`, for the report.
    pub fn label(&self) -> String {
        format!("{} ({} cores)", self.cpu, self.cores)
    }
}

/// The first `model name` (x86) or `Hardware`/`CPU part` line's value of `/proc/cpuinfo` text.
fn cpu_model(cpuinfo: &str) -> Option<String> {
    ["model name", "Hardware", "Processor", "CPU part"]
        .iter()
        .find_map(|key| {
            cpuinfo.lines().find_map(|line| {
                let (k, v) = line.split_once(':')?;
                (k.trim() == *key && !v.trim().is_empty()).then(|| v.trim().to_string())
            })
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_model_reads_the_first_model_name() {
        let text = "processor\t: 0\nvendor_id\t: GenuineIntel\nmodel name\t: Intel(R) Xeon(R), 2.9GHz\n\
                    processor\t: 1\nmodel name\t: other\n";
        assert_eq!(cpu_model(text).as_deref(), Some("Intel(R) Xeon(R), 2.9GHz"));
        assert_eq!(cpu_model("processor : 0\n"), None);
        assert_eq!(
            cpu_model("Hardware : BCM2835\n").as_deref(),
            Some("BCM2835")
        );
    }

    #[test]
    fn this_host_is_one_field() {
        let h = Host::this();
        assert!(h.cores >= 1);
        assert!(!h.cpu.is_empty());
        assert!(!h.cpu.contains([',', '\t', '\n']));
    }
}
