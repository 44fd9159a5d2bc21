//! Per-step recording: the digest of every step, TDMA cycle and epoch row (see
//! [`super::digest`]), decimated rows of `trace.csv` with the net's invariants (and, on
//! request, each traced body's rotation), the few series the plots need (kept in memory;
//! the full trace is streamed to disk), and what summary.json reports of the invariants'
//! drift and the SMC boundary layer ([`super::drift`]).

use std::io::Write;

use crate::control::experiment::WindowReport;
use crate::cosim::{EpochRecord, Observer, StepValues};
use crate::output::AtomicFile;
use crate::report::Series;
use crate::scenario::model::Scenario;

use super::drift::{undriven_stretches, InvariantLog, LayerWatch};
use super::joint_work::JointWork;
use super::network_log::NetworkLog;
use super::plot_samples::PlotSamples;
use super::Digest;
use crate::network::tdma::CycleReport;

/// At most this many links get their own series in the constraint plot; larger models
/// plot the envelope `max_l |w_l|` only.
pub const MAX_PLOTTED_LINKS: usize = 24;

/// Bytes of a trace row held before they go to the file (and the text hash, and the
/// lines kept for checkpoints): the same bytes in the same order as the whole row.
const SPILL: usize = 1 << 16;

/// The columns of the net's invariants on every trace row, after the bodies' (see
/// [`super::Invariants`]): total momentum [kg·m/s], angular momentum about the centre of
/// mass [kg·m²/s], kinetic energy [J].
pub const INVARIANT_COLUMNS: [&str; 7] = ["Px", "Py", "Pz", "Lx", "Ly", "Lz", "KE"];

/// The columns of each traced body's rotation with `output.trace_rotation`, after the
/// invariants (`<name>_B<id>`): orientation quaternion (body → world) and world angular
/// velocity [rad/s].
pub const ROTATION_COLUMNS: [&str; 7] = ["qw", "qx", "qy", "qz", "wx", "wy", "wz"];

/// Records a run's steps. Serializable (without its open file) so that a checkpoint
/// carries the digest chain, the plot series and, when kept, the trace text so far.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Recorder {
    decimation: u64,
    link_count: usize,
    /// Each row's name where the scene has joints (empty: links only, `L<k>`).
    row_names: Vec<String>,
    trace_bodies: Vec<usize>,
    plot_bodies: Vec<(usize, u32)>,
    #[serde(skip)]
    file: Option<AtomicFile>,
    #[serde(skip)]
    line: String,
    /// BLAKE3 of every byte written to trace.csv so far (a restored recorder hashes its
    /// kept lines again as it writes them to the new file).
    #[serde(skip)]
    text_hash: blake3::Hasher,
    /// Every trace line written so far, kept when checkpoints are written.
    kept: Option<String>,
    /// The epoch chain: every epochs.csv row (see [`super::digest`]).
    epochs: Digest,
    /// The dynamics chain: steps and TDMA cycles, the live dynamics whatever is measured
    /// beside them.
    dynamics: Digest,
    rows: u64,
    /// Per link (models of at most [`MAX_PLOTTED_LINKS`] links) then the envelope `max |w|`
    /// as peak series, or (larger models) the largest, smallest and RMS `w` over the
    /// links; x, y, z of each plotted body as first series. Bounded in length whatever
    /// the horizon.
    plots: PlotSamples,
    /// Larger models: each link's largest `|w|` over every step so far, to name the
    /// worst links in the plot.
    link_peaks: Vec<f64>,
    /// network.csv and the timeline cycles, on a TDMA scene.
    network: Option<NetworkLog>,
    /// Whether each traced body's orientation and angular velocity go into the trace
    /// (`output.trace_rotation`).
    rotation: bool,
    /// The invariants at the start, the end and the undriven stretches.
    invariants: InvariantLog,
    /// The SMC boundary layer's account (SMC runs built with [`Recorder::for_scenario`]).
    layer: Option<LayerWatch>,
    /// The work the law does on the joints' rows (scenes with joints built with
    /// [`Recorder::for_scenario`]).
    joint_work: Option<JointWork>,
    /// The names of the FMU outputs recorded per step (`<fmu>.<variable>`), trace.csv's
    /// last columns; empty without FMUs.
    #[serde(default)]
    signal_names: Vec<String>,
    /// The traced FMU outputs for signals.svg, one first series each, bounded in length
    /// as `plots`.
    #[serde(default = "no_plot_samples")]
    signal_plots: PlotSamples,
}

fn no_plot_samples() -> PlotSamples {
    PlotSamples::new(0, 0)
}

impl Recorder {
    /// A recorder writing `trace.csv` to `file` (or only digesting, if `None`).
    /// `body_ids[i]` is the file id of body index `i`.
    pub fn new(
        file: Option<AtomicFile>,
        decimation: u64,
        link_count: usize,
        body_ids: &[u32],
        trace_bodies: &[usize],
        plot_bodies: &[usize],
    ) -> std::io::Result<Recorder> {
        let mut r =
            Recorder::unwritten(decimation, link_count, body_ids, trace_bodies, plot_bodies);
        if let Some(f) = file {
            r.start_file(f, body_ids)?;
        }
        Ok(r)
    }

    /// The recorder `dsmcosim run` uses for `scenario`, writing `trace.csv` to `file`
    /// (or only digesting, if `None`): the scenario's decimation, traced and plotted
    /// bodies and `trace_rotation`; the undriven stretches of its forces, and on SMC its
    /// boundary layer, followed for summary.json.
    pub fn for_scenario(
        file: Option<AtomicFile>,
        scenario: &Scenario,
    ) -> std::io::Result<Recorder> {
        let ids: Vec<u32> = scenario.bodies.iter().map(|b| b.id).collect();
        let out = &scenario.output;
        let mut r = Recorder::unwritten(
            out.decimation,
            scenario.links.len(),
            &ids,
            &out.trace_bodies,
            &out.plot_bodies,
        );
        r.rotation = out.trace_rotation;
        if r.rotation {
            // The plotted bodies' angular velocities besides their coordinates.
            r.plots = PlotSamples::new(r.plots.peaks.len(), 6 * r.plot_bodies.len());
        }
        if scenario.links.iter().any(|l| l.joint.is_some()) {
            r.row_names = scenario
                .links
                .iter()
                .enumerate()
                .map(|(k, l)| l.name(k))
                .collect();
        }
        r.invariants = InvariantLog::new(&undriven_stretches(scenario));
        r.layer = LayerWatch::new(scenario);
        r.joint_work = JointWork::new(scenario);
        r.signal_names = scenario.signal_names();
        r.signal_plots = PlotSamples::new(0, r.signal_names.len());
        if let Some(f) = file {
            r.start_file(f, &ids)?;
        }
        Ok(r)
    }

    /// A recorder without a trace file yet.
    fn unwritten(
        decimation: u64,
        link_count: usize,
        body_ids: &[u32],
        trace_bodies: &[usize],
        plot_bodies: &[usize],
    ) -> Recorder {
        Recorder {
            decimation: decimation.max(1),
            link_count,
            row_names: Vec::new(),
            trace_bodies: trace_bodies.to_vec(),
            plot_bodies: plot_bodies.iter().map(|&i| (i, body_ids[i])).collect(),
            file: None,
            line: String::new(),
            text_hash: blake3::Hasher::new(),
            kept: None,
            epochs: Digest::new(),
            dynamics: Digest::new(),
            rows: 0,
            plots: PlotSamples::new(
                if link_count > MAX_PLOTTED_LINKS {
                    3
                } else {
                    link_count + 1
                },
                3 * plot_bodies.len(),
            ),
            link_peaks: if link_count > MAX_PLOTTED_LINKS {
                vec![0.0; link_count]
            } else {
                Vec::new()
            },
            network: None,
            rotation: false,
            invariants: InvariantLog::new(&[]),
            layer: None,
            joint_work: None,
            signal_names: Vec::new(),
            signal_plots: no_plot_samples(),
        }
    }

    /// Row `k`'s name (0-based): `L<k+1>`, or a joint row's `J<j>_<r>`.
    fn row_name(&self, k: usize) -> String {
        self.row_names
            .get(k)
            .cloned()
            .unwrap_or_else(|| crate::scenario::model::row_name(k, None))
    }

    /// Writes the header to `file`, which the trace goes to from now on. `body_ids[i]`
    /// is the file id of body index `i`.
    fn start_file(&mut self, mut file: AtomicFile, body_ids: &[u32]) -> std::io::Result<()> {
        let mut head = String::from("t");
        for k in 0..self.link_count {
            head.push_str(&format!(",w_{}", self.row_name(k)));
        }
        for k in 0..self.link_count {
            head.push_str(&format!(",f_{}", self.row_name(k)));
        }
        for &i in &self.trace_bodies {
            let id = body_ids[i];
            for ax in ["px", "py", "pz", "vx", "vy", "vz"] {
                head.push_str(&format!(",{ax}_B{id}"));
            }
        }
        // A scene without bodies (FMUs only) has no momenta or energy to show.
        if !body_ids.is_empty() {
            for name in INVARIANT_COLUMNS {
                head.push_str(&format!(",{name}"));
            }
        }
        if self.rotation {
            for &i in &self.trace_bodies {
                let id = body_ids[i];
                for name in ROTATION_COLUMNS {
                    head.push_str(&format!(",{name}_B{id}"));
                }
            }
        }
        for name in &self.signal_names {
            // An FMU's variable names may hold what CSV quotes (`a,b`, `"x"`).
            head.push(',');
            head.push_str(&crate::output::csv_field(name));
        }
        self.line = format!("{head}\n");
        file.write_all(self.line.as_bytes())?;
        self.text_hash.update(self.line.as_bytes());
        self.file = Some(file);
        Ok(())
    }

    /// Records one step: digest always, CSV row and plot samples when the step is kept.
    pub fn record(&mut self, s: &StepValues) -> std::io::Result<()> {
        let d = &mut self.dynamics;
        d.time(s.time.as_nanos());
        d.values(s.w);
        d.values(s.f);
        for p in s.p {
            d.values(p.as_slice());
        }
        for v in s.v {
            d.values(v.as_slice());
        }
        d.signals(s.signals);
        d.end_step();
        for (peak, w) in self.link_peaks.iter_mut().zip(s.w) {
            *peak = peak.max(w.abs());
        }
        if let Some(layer) = &mut self.layer {
            layer.record(s.time, s.max_w);
        }
        if let Some(work) = &mut self.joint_work {
            work.record(s.time, s.f, s.w);
        }
        let row = s.step.is_multiple_of(self.decimation) || s.last;
        // The invariants cost a pass over the bodies: computed on the rows the trace
        // keeps and the few steps summary.json needs, not on every step.
        if !row && !self.invariants.wants(s.step) {
            return Ok(());
        }
        let invariants = s.invariants();
        if let Some(work) = &mut self.joint_work {
            work.kinetic(invariants.kinetic_energy);
        }
        self.invariants.record(s.step, s.time, invariants, row);
        if !row {
            return Ok(());
        }
        self.rows += 1;
        let t = s.time.as_secs_f64();
        if !s.signals.is_empty() {
            // Numbers and Booleans are plotted; a String or Binary column has no curve
            // (NaN, which signals.svg leaves out).
            let numbers = s.signals.iter().map(|v| v.as_f64().unwrap_or(f64::NAN));
            self.signal_plots.push(t, std::iter::empty(), numbers);
        }
        let omega = |i: usize, ax: usize| s.omega.get(i).map_or(0.0, |w| w[ax]);
        let spins = self
            .plot_bodies
            .iter()
            .filter(|_| self.rotation)
            .flat_map(|&(i, _)| (0..3).map(move |ax| omega(i, ax)));
        let bodies = self
            .plot_bodies
            .iter()
            .flat_map(|&(i, _)| (0..3).map(move |ax| s.p[i][ax]))
            .chain(spins);
        if self.link_peaks.is_empty() {
            let envelope = s.w.iter().fold(0.0, |m: f64, w| m.max(w.abs()));
            let links = s.w.iter().copied();
            self.plots
                .push(t, links.chain(std::iter::once(envelope)), bodies);
        } else {
            let (mut max, mut min, mut squares) = (f64::NEG_INFINITY, f64::INFINITY, 0.0);
            for &w in s.w {
                max = max.max(w);
                min = min.min(w);
                squares += w * w;
            }
            let rms = (squares / s.w.len().max(1) as f64).sqrt();
            self.plots.push(t, [max, min, rms], bodies);
        }
        let Some(file) = &mut self.file else {
            return Ok(());
        };
        // Hand-written rather than `csv::Writer` (see `crate::output::csv_text`), for a
        // measured reason: this is the hot path, every field is a number (the header's
        // names are `[A-Za-z0-9_]`), so there is nothing to quote, and with
        // `csv::Writer::write_field` of the same text the bytes were equal but a run of
        // scenarios/grid16_monolithic.json with `--set /output/decimation=1` (84 MB of
        // trace, 10 runs each) took 3 % more CPU time (0.602 s against 0.583 s user);
        // it would also need a second buffer for the lines kept for checkpoints.
        //
        // The row goes out in pieces of about [`SPILL`] bytes: a million-body grid's
        // row is 150 MB of text, which held whole (and grown by doubling) was the peak
        // of its run.
        use std::fmt::Write as _;
        let (line, kept, hash) = (&mut self.line, &mut self.kept, &mut self.text_hash);
        let mut out = |line: &mut String, at_least: usize| -> std::io::Result<()> {
            if line.len() < at_least {
                return Ok(());
            }
            if let Some(kept) = kept.as_mut() {
                kept.push_str(line);
            }
            hash.update(line.as_bytes());
            file.write_all(line.as_bytes())?;
            line.clear();
            Ok(())
        };
        line.clear();
        let _ = write!(line, "{t}");
        for x in s.w.iter().chain(s.f) {
            let _ = write!(line, ",{x}");
            out(line, SPILL)?;
        }
        for &i in &self.trace_bodies {
            let (p, v) = (s.p[i], s.v[i]);
            for x in p.iter().chain(v.iter()) {
                let _ = write!(line, ",{x}");
            }
            out(line, SPILL)?;
        }
        if !s.bodies.is_empty() {
            let (m, l) = (&invariants.momentum, &invariants.angular_momentum);
            for x in m.iter().chain(l.iter()) {
                let _ = write!(line, ",{x}");
            }
            let _ = write!(line, ",{}", invariants.kinetic_energy);
        }
        if self.rotation {
            for &i in &self.trace_bodies {
                // Point masses have no rotation state: identity and zero.
                let (q, w) = match (s.q.get(i), s.omega.get(i)) {
                    (Some(q), Some(w)) => ([q.w, q.i, q.j, q.k], *w),
                    _ => ([1.0, 0.0, 0.0, 0.0], nalgebra::Vector3::zeros()),
                };
                for x in q.iter().chain(w.iter()) {
                    let _ = write!(line, ",{x}");
                }
                out(line, SPILL)?;
            }
        }
        for x in s.signals {
            // An FMU output of any type: a String CSV-quoted where needed
            // ([`crate::fmu::Value::write_csv`]).
            line.push(',');
            x.write_csv(line);
            out(line, SPILL)?;
        }
        line.push('\n');
        out(line, 0)
    }

    /// The run digest so far (hex): both chains, so every step, TDMA cycle and epoch row.
    pub fn digest(&self) -> String {
        Digest::combined_hex(&self.dynamics, &self.epochs)
    }

    /// The dynamics digest so far (hex): the chain over the step and TDMA cycle records
    /// only, so that it is equal for two runs of the same live dynamics whatever they
    /// measured beside it (a controller's baselines, grid search, forks).
    pub fn dynamics_digest(&self) -> String {
        self.dynamics.hex()
    }

    /// Rows written to the trace.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// summary.json's `invariants` ([`InvariantLog::summary`]); `None` before any step.
    pub fn invariants_summary(&self) -> Option<serde_json::Value> {
        self.invariants.summary()
    }

    /// The SMC boundary layer's account; `None` under Baumgarte or for a recorder not
    /// built with [`Recorder::for_scenario`].
    pub fn boundary_layer(&self) -> Option<&LayerWatch> {
        self.layer.as_ref()
    }

    /// The work the law did on the joints' rows; `None` on a scene without joints or
    /// for a recorder not built with [`Recorder::for_scenario`].
    pub fn joint_work(&self) -> Option<&JointWork> {
        self.joint_work.as_ref()
    }

    /// Keeps a copy of every trace line from now on (the header included), for
    /// checkpoints.
    pub fn keep_lines(&mut self) {
        if self.kept.is_none() {
            self.kept = Some(std::mem::take(&mut self.line));
        }
        if let Some(n) = &mut self.network {
            n.keep_lines();
        }
    }

    /// Records the TDMA cycles of the run into `log` (network.csv).
    pub fn attach_network(&mut self, log: NetworkLog) {
        self.network = Some(log);
    }

    /// The TDMA log, on a TDMA scene.
    pub fn network(&self) -> Option<&NetworkLog> {
        self.network.as_ref()
    }

    /// Attaches a new network.csv to a restored recorder (a TDMA run's) and writes the
    /// kept lines to it.
    pub fn reattach_network(&mut self, file: AtomicFile) -> std::io::Result<()> {
        match &mut self.network {
            Some(n) => n.reattach(file),
            None => Ok(()),
        }
    }

    /// Attaches a new trace file to a restored recorder and writes the kept lines to it.
    pub fn reattach(&mut self, mut file: AtomicFile) -> std::io::Result<()> {
        if let Some(kept) = &self.kept {
            file.write_all(kept.as_bytes())?;
            self.text_hash = blake3::Hasher::new();
            self.text_hash.update(kept.as_bytes());
        }
        self.file = Some(file);
        Ok(())
    }

    /// BLAKE3 (hex) of the bytes written to trace.csv; `None` for a recorder without a
    /// trace file.
    pub fn trace_digest(&self) -> Option<String> {
        self.file
            .as_ref()
            .map(|_| self.text_hash.finalize().to_hex().to_string())
    }

    /// Closes the trace file (renaming it into place).
    pub fn commit(&mut self) -> crate::Result<()> {
        if let Some(n) = &mut self.network {
            n.commit()?;
        }
        match self.file.take() {
            Some(f) => f.commit(),
            None => Ok(()),
        }
    }

    /// Series for the constraint plot: one per link (small models) or the envelope.
    ///
    /// Past [`MAX_PLOTTED_LINKS`] links the recorder keeps the envelope only: one series,
    /// the RMS of `w` over the links with a band from the smallest to the largest, whose
    /// label names the [`WORST_NAMED`] links of largest `|w|` over the run with that value.
    pub fn constraint_series(&self) -> Vec<Series> {
        let p = &self.plots;
        if !self.link_peaks.is_empty() {
            let band = p
                .times
                .iter()
                .zip(&p.peaks[0])
                .zip(&p.peaks[1])
                .map(|((&t, &max), &min)| (t, min, max))
                .collect();
            let mut order: Vec<usize> = (0..self.link_peaks.len()).collect();
            order.sort_by(|&a, &b| {
                self.link_peaks[b]
                    .total_cmp(&self.link_peaks[a])
                    .then(a.cmp(&b))
            });
            let worst: Vec<String> = order
                .iter()
                .take(WORST_NAMED)
                .map(|&k| format!("{} {:.3} m", self.row_name(k), self.link_peaks[k]))
                .collect();
            return vec![Series::new(
                format!(
                    "RMS of {} links, band min–max; largest |w|: {}",
                    self.link_count,
                    worst.join(", ")
                ),
                zip(&p.times, &p.peaks[2]),
            )
            .with_band(band)];
        }
        p.peaks[..self.link_count]
            .iter()
            .enumerate()
            .map(|(k, s)| Series::new(self.row_name(k), zip(&p.times, s)))
            .collect()
    }

    /// Series for the body-coordinate plot: x, y, z of each plotted body.
    pub fn body_series(&self) -> Vec<Series> {
        let mut out = Vec::new();
        let p = &self.plots;
        for (series, &(_, id)) in p.firsts.chunks(3).zip(&self.plot_bodies) {
            for (ax, s) in ["x", "y", "z"].iter().zip(series) {
                out.push(Series::new(format!("{ax} of B{id}"), zip(&p.times, s)));
            }
        }
        out
    }

    /// Series for signals.svg: each traced FMU output, named as its trace column;
    /// empty without FMUs.
    pub fn signal_series(&self) -> Vec<Series> {
        let p = &self.signal_plots;
        self.signal_names
            .iter()
            .zip(&p.firsts)
            // A String or Binary column (all NaN here) has no curve.
            .filter(|(_, s)| s.iter().any(|v| !v.is_nan()))
            .map(|(name, s)| Series::new(name.clone(), zip(&p.times, s)))
            .collect()
    }

    /// Series for the angular-velocity plot (with `output.trace_rotation`): ωx, ωy, ωz
    /// of each plotted body in the world frame; empty without.
    pub fn angular_velocity_series(&self) -> Vec<Series> {
        let p = &self.plots;
        let n = self.plot_bodies.len();
        if !self.rotation || p.firsts.len() < 6 * n {
            return Vec::new();
        }
        let mut out = Vec::new();
        for (series, &(_, id)) in p.firsts[3 * n..].chunks(3).zip(&self.plot_bodies) {
            for (ax, s) in ["ωx", "ωy", "ωz"].iter().zip(series) {
                out.push(Series::new(format!("{ax} of B{id}"), zip(&p.times, s)));
            }
        }
        out
    }
}

impl Observer for Recorder {
    fn on_step(&mut self, values: &StepValues) -> std::io::Result<()> {
        self.record(values)
    }

    /// A TDMA cycle: its record goes into the dynamics chain (see [`super::digest`])
    /// and its frames into network.csv.
    fn on_cycle(&mut self, report: &CycleReport) -> std::io::Result<()> {
        let d = &mut self.dynamics;
        d.time(report.start.as_nanos());
        for f in &report.frames {
            d.count(f.slot as u64);
            d.count(f.sender as u64);
            d.time(f.start.as_nanos());
            d.time(f.delivery.map_or(u64::MAX, |d| d.as_nanos()));
        }
        d.end_step();
        match &mut self.network {
            Some(n) => n.record(report),
            None => Ok(()),
        }
    }

    /// A closed window: the world's columns of its epochs.csv row go into the epoch
    /// chain.
    fn on_epoch(&mut self, e: &EpochRecord) {
        let d = &mut self.epochs;
        d.time(e.t_start.as_nanos());
        d.time(e.t_end.as_nanos());
        for &(requested, achieved) in &e.taus {
            d.values(&[requested, achieved]);
        }
        d.values(&[e.bandwidth, e.cost]);
        d.end_step();
    }

    /// A window the controller ran: the controller's columns of its epochs.csv row go
    /// into the epoch chain.
    fn on_window(&mut self, w: &WindowReport) {
        let d = &mut self.epochs;
        d.value(w.live.objective);
        for b in &w.baselines {
            d.value(b.candidate.objective);
        }
        match &w.grid_best {
            Some(c) => {
                d.count(c.x.len() as u64);
                d.values(&c.x);
            }
            None => d.count(0),
        }
        d.count(w.dsm_path.len() as u64);
        d.end_step();
    }
}

/// Links with their own series in the constraint plot (none on larger models, which
/// plot the envelope only).
/// Links named by their largest `|w|` in the envelope of a larger model.
pub const WORST_NAMED: usize = 4;

fn zip(t: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    t.iter().copied().zip(y.iter().copied()).collect()
}

#[cfg(test)]
mod tests {

    /// Past MAX_PLOTTED_LINKS links the plot keeps the envelope: the RMS with a band from
    /// the smallest to the largest w at each row, and names the links of largest |w|
    /// over every step (also between plotted rows).
    #[test]
    fn a_large_model_plots_the_envelope_and_names_its_worst_links() {
        let n = MAX_PLOTTED_LINKS + 6;
        let mut r = Recorder::new(None, 2, n, &[1], &[], &[]).unwrap();
        let zero = nalgebra::Vector3::zeros();
        let (f, p, v) = (vec![0.0; n], vec![zero; 1], vec![zero; 1]);
        for step in 0..4u64 {
            let mut w = vec![0.01; n];
            w[3] = -0.5; // the largest magnitude, on plotted rows
            if step == 1 {
                w[20] = 0.9; // larger still, on a row the plot skips (decimation 2)
            }
            r.record(&StepValues {
                signals: &[],
                step,
                time: SimTime(step * 1_000_000),
                last: step == 3,
                w: &w,
                f: &f,
                p: &p,
                v: &v,
                q: &[],
                omega: &[],
                max_w: 0.9,
                bodies: &[],
            })
            .unwrap();
        }
        let series = r.constraint_series();
        assert_eq!(series.len(), 1);
        let label = &series[0].label;
        assert!(
            label.starts_with(&format!(
                "RMS of {n} links, band min–max; largest |w|: L21 0.900 m, L4 0.500 m"
            )),
            "{label}"
        );
        // Rows 0, 2 and the last (3): band [-0.5, 0.01], RMS of one -0.5 and n-1 times 0.01.
        let rms = ((0.25 + (n - 1) as f64 * 1e-4) / n as f64).sqrt();
        assert_eq!(series[0].points.len(), 3);
        assert!((series[0].points[0].1 - rms).abs() < 1e-15);
        assert_eq!((series[0].band[0].1, series[0].band[0].2), (-0.5, 0.01));
    }
    use super::*;
    use crate::control::experiment::{BaselineResult, Candidate};
    use crate::kernel::SimTime;

    fn epoch(cost: f64) -> EpochRecord {
        EpochRecord {
            t_start: SimTime::ZERO,
            t_end: SimTime(1_000_000_000),
            cost,
            taus: vec![(0.005, 0.005)],
            bandwidth: 200.0,
        }
    }

    fn window(objective: f64, grid: Option<Vec<f64>>) -> WindowReport {
        let c = |x: Vec<f64>, objective| Candidate { x, objective };
        WindowReport {
            t_start: SimTime::ZERO,
            t_end: SimTime(1_000_000_000),
            live: c(vec![0.005], 0.5),
            baselines: vec![BaselineResult {
                name: "no_opt".into(),
                candidate: c(vec![0.005], objective),
            }],
            grid_best: grid.map(|x| c(x, 0.25)),
            dsm_path: Vec::new(),
        }
    }

    /// (digest, dynamics digest) after one epoch row.
    fn digests(e: &EpochRecord, w: Option<&WindowReport>) -> (String, String) {
        let mut r = Recorder::new(None, 1, 1, &[1], &[], &[]).unwrap();
        r.on_epoch(e);
        if let Some(w) = w {
            r.on_window(w);
        }
        (r.digest(), r.dynamics_digest())
    }

    #[test]
    fn every_epoch_value_reaches_the_digest_but_not_the_dynamics_digest() {
        let base = digests(&epoch(0.1), Some(&window(0.3, None)));
        let next_up = f64::from_bits(0.1f64.to_bits() + 1);
        let changed = [
            digests(&epoch(next_up), Some(&window(0.3, None))),
            digests(&epoch(0.1), Some(&window(-0.3, None))),
            digests(&epoch(0.1), Some(&window(0.3, Some(vec![0.004])))),
            digests(&epoch(0.1), None),
        ];
        for (i, c) in changed.iter().enumerate() {
            assert_ne!(c.0, base.0, "change {i}");
            assert_eq!(c.1, base.1, "change {i}: the dynamics digest has no epochs");
        }
        let mut taus = epoch(0.1);
        taus.taus[0].1 = 0.006;
        assert_ne!(digests(&taus, Some(&window(0.3, None))).0, base.0);
    }
}
