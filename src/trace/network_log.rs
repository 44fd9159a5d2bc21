//! `network.csv` of a TDMA run (one row per frame) and the few cycles the slot-timeline
//! plot draws.
//!
//! Columns: `cycle,slot,sender,kind,channel,bytes,nominal,send_time,delivery_time,lost,
//! latency,info` — times in seconds with all nine decimals of the nanosecond clock
//! (exact), `delivery_time` and `latency` empty for a lost frame; `kind` is `sync`,
//! `static` (protocol: `info` says which list fragment it broadcasts or which list it
//! confirms) or `data` (`channel` names the channel). Rows of every
//! `network_decimation`-th cycle are written, and every lost frame and every cycle in
//! which a list goes into force whatever the decimation. Rows are written with the `csv`
//! crate ([`crate::output::csv_text`]); the numbers and times are formatted here.

use std::io::Write as _;

use crate::kernel::SimTime;
use crate::network::tdma::collision::{FrameKind, Transmission};
use crate::network::tdma::CycleReport;
use crate::output::AtomicFile;

/// The header of network.csv.
pub const HEADER: &str =
    "cycle,slot,sender,kind,channel,bytes,nominal,send_time,delivery_time,lost,latency,info";

/// Writes network.csv and keeps the cycles for the timeline plot.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct NetworkLog {
    decimation: u64,
    timeline_cycles: usize,
    channel_names: Vec<String>,
    #[serde(skip)]
    file: Option<AtomicFile>,
    /// Every line written so far, kept when checkpoints are written.
    kept: Option<String>,
    timeline: Vec<CycleReport>,
    /// The timeline shows the first loss (once one happened).
    timeline_has_loss: bool,
    previous: Option<CycleReport>,
    frames: u64,
    lost: u64,
}

impl NetworkLog {
    /// A log writing to `file`, keeping every `decimation`-th cycle and
    /// `timeline_cycles` cycles for the plot.
    pub fn new(
        file: Option<AtomicFile>,
        decimation: u64,
        timeline_cycles: u64,
        channel_names: Vec<String>,
    ) -> std::io::Result<NetworkLog> {
        let mut log = NetworkLog {
            decimation: decimation.max(1),
            timeline_cycles: timeline_cycles.max(1) as usize,
            channel_names,
            file,
            kept: None,
            timeline: Vec::new(),
            timeline_has_loss: false,
            previous: None,
            frames: 0,
            lost: 0,
        };
        log.write(&format!("{HEADER}\n"))?;
        Ok(log)
    }

    /// Keeps a copy of every line from now on (the header included), for checkpoints.
    pub fn keep_lines(&mut self) {
        if self.kept.is_none() {
            self.kept = Some(format!("{HEADER}\n"));
        }
    }

    /// Attaches a new file to a restored log and writes the kept lines to it.
    pub fn reattach(&mut self, mut file: AtomicFile) -> std::io::Result<()> {
        if let Some(kept) = &self.kept {
            file.write_all(kept.as_bytes())?;
        }
        self.file = Some(file);
        Ok(())
    }

    /// Closes the file (renaming it into place).
    pub fn commit(&mut self) -> crate::Result<()> {
        match self.file.take() {
            Some(f) => f.commit(),
            None => Ok(()),
        }
    }

    /// Frames seen so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Frames lost so far.
    pub fn lost(&self) -> u64 {
        self.lost
    }

    /// The cycles for the slot-timeline plot: the first ones, or, once a frame was
    /// lost, the cycle before the first loss, that cycle and the ones after it.
    pub fn timeline(&self) -> &[CycleReport] {
        &self.timeline
    }

    /// Records one cycle.
    pub fn record(&mut self, report: &CycleReport) -> std::io::Result<()> {
        let lost = report.lost();
        self.frames += report.frames.len() as u64;
        self.lost += lost as u64;
        self.keep_for_timeline(report, lost > 0);
        let every = report.cycle.is_multiple_of(self.decimation) || report.switch.is_some();
        let rows: Vec<[String; 12]> = report
            .frames
            .iter()
            .filter(|f| every || f.lost())
            .map(|f| self.row(f))
            .collect();
        if !rows.is_empty() {
            self.write(&crate::output::csv_text(rows))?;
        }
        Ok(())
    }

    fn keep_for_timeline(&mut self, report: &CycleReport, lost: bool) {
        if lost && !self.timeline_has_loss {
            self.timeline_has_loss = true;
            self.timeline = self.previous.take().into_iter().collect();
            self.timeline.push(report.clone());
        } else if self.timeline.len() < self.timeline_cycles {
            self.timeline.push(report.clone());
        }
        if !self.timeline_has_loss {
            self.previous = Some(report.clone());
        }
    }

    /// The fields of `f`'s row.
    fn row(&self, f: &Transmission) -> [String; 12] {
        let (kind, channel, info) = match f.kind {
            FrameKind::Sync => ("sync", "", String::new()),
            FrameKind::Static {
                broadcast,
                confirms,
            } => {
                let mut info = String::new();
                if let Some(b) = broadcast {
                    info = format!("list v{} fragment {}/{}", b.version, b.index + 1, b.of);
                }
                if let Some(v) = confirms {
                    info = format!("confirms list v{v}");
                }
                ("static", "", info)
            }
            FrameKind::Dynamic { channel } => (
                "data",
                self.channel_names
                    .get(channel)
                    .map(String::as_str)
                    .unwrap_or("?"),
                String::new(),
            ),
        };
        let (delivery, lost, latency) = match (f.delivery, f.latency()) {
            (Some(d), Some(l)) => (secs(d), "0", secs(l)),
            _ => (String::new(), "1", String::new()),
        };
        [
            f.cycle.to_string(),
            f.slot.to_string(),
            f.sender.to_string(),
            kind.to_string(),
            channel.to_string(),
            f.bytes.to_string(),
            secs(f.nominal),
            secs(f.start),
            delivery,
            lost.to_string(),
            latency,
            info,
        ]
    }

    fn write(&mut self, text: &str) -> std::io::Result<()> {
        if let Some(kept) = &mut self.kept {
            kept.push_str(text);
        }
        match &mut self.file {
            Some(f) => f.write_all(text.as_bytes()),
            None => Ok(()),
        }
    }
}

/// Exact seconds of a nanosecond time: `12.345678901`.
fn secs(t: SimTime) -> String {
    format!("{}.{:09}", t.0 / 1_000_000_000, t.0 % 1_000_000_000)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seconds_are_exact() {
        assert_eq!(secs(SimTime(1)), "0.000000001");
        assert_eq!(secs(SimTime(12_345_678_901)), "12.345678901");
    }
}
