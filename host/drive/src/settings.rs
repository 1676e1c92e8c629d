//! Every parameter of a run, as TOML: a preset's defaults, then `--config FILE`, then
//! `--set SECTION.KEY=VALUE`, then the command line's named flags.
//! The `config.toml` a run writes holds the values actually used and can be passed back with
//! `--config` to repeat the run. `--config` also reads kiss-icp's YAML (a `.yaml` or `.yml`
//! file, [`Settings::from_kiss_icp_yaml`]).

use anyhow::{bail, Context, Result};
use kiss_odom_core::{Capacities, Config, Degeneracy, Real, Robust};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Scalar type the core runs on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Scalar {
    /// Double precision: agrees with the reference to rounding.
    F64,
    /// Single precision: half the memory, what microcontrollers run.
    F32,
}

/// How map points are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Storage {
    /// Points as they are.
    Exact,
    /// 16-bit offsets inside the voxel (6 bytes a point).
    Quantized,
}

/// Registration along directions the scene does not constrain (`kiss_odom_core::Degeneracy`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum DegeneracyMode {
    /// As kiss-icp 1.3.0 (default).
    #[default]
    Reference,
    /// Point-to-plane terms where the map is planar (tunnels, corridors, long walls, open
    /// ground); with its own defaults for the voxel size, kernel and capacities.
    Robust,
}

impl From<DegeneracyMode> for Degeneracy {
    fn from(m: DegeneracyMode) -> Self {
        match m {
            DegeneracyMode::Reference => Degeneracy::Reference,
            DegeneracyMode::Robust => Degeneracy::Robust,
        }
    }
}

/// The set of defaults a run starts from (`[pipeline] preset`, `--preset`): every setting
/// not given takes the preset's value.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum PresetName {
    /// kiss-icp 1.3.0's parameters: its poses, bit for bit.
    #[default]
    Default,
    /// The lowest error measured here, at one to three times the default's time
    /// (`Config::accurate`; the book's configuration reference lists what it changes).
    Accurate,
}

/// Which defaults the settings start from.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Pipeline {
    /// `default` or `accurate`.
    pub preset: PresetName,
}

impl From<Degeneracy> for DegeneracyMode {
    fn from(d: Degeneracy) -> Self {
        match d {
            Degeneracy::Reference => DegeneracyMode::Reference,
            Degeneracy::Robust => DegeneracyMode::Robust,
        }
    }
}

/// Sensor data handling (the reference's `data` section).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Data {
    /// `r_max` (m).
    pub max_range: f64,
    /// Minimum range (m).
    pub min_range: f64,
    /// Deskew scans with per-point timestamps.
    pub deskew: bool,
    /// Deskew each scan a second time with the motion its first registration found, and
    /// register it again (the `accurate` preset's; not the reference's).
    pub redeskew: bool,
}

/// Local map and downsampling (the reference's `mapping` section plus alpha/beta).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Mapping {
    /// Voxel size `v` (m); omitted means `max_range / 100`.
    pub voxel_size: Option<f64>,
    /// `N_max`.
    pub max_points_per_voxel: u32,
    /// Merge-cloud voxel factor.
    pub alpha: f64,
    /// Registration-cloud voxel factor.
    pub beta: f64,
    /// Keep the downsampled clouds in kiss-icp's order, which its poses need bit for bit
    /// (`Config::reference_order`); `false`: in the scan's order, faster.
    pub reference_order: bool,
    /// A registration cloud of more points is made again with coarser voxels
    /// (`Config::desired_source_points`; 0: never).
    pub desired_source_points: usize,
}

/// Adaptive threshold.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Threshold {
    /// `tau_0` (m).
    pub initial_threshold: f64,
    /// `delta_min` (m).
    pub min_motion_th: f64,
}

/// ICP.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Registration {
    /// Iteration cap.
    pub max_num_iterations: u32,
    /// `gamma`.
    pub convergence_criterion: f64,
    /// Geman-McClure scale as a multiple of sigma (reference 1, paper 1/3); omitted means 1.
    pub kernel_scale: Option<f64>,
    /// Correspondence threshold as a multiple of sigma.
    pub max_correspondence_factor: f64,
    /// Observability ratio below which a frame is flagged degenerate.
    pub degeneracy_ratio: f64,
    /// Robust mode registers a frame again with plane terms when the reference registration's
    /// observability is below this (`Robust::plane_gate`); 1 or more: every frame.
    pub plane_gate: f64,
    /// Robust mode's hold prior per correspondence: registrations with plane terms are pulled
    /// to the constant-velocity prediction (`Robust::prediction_prior`); 0: none.
    pub prediction_prior: f64,
    /// Robust mode's vehicle prior per correspondence: no sideways motion along the sensor's
    /// y axis (`Robust::lateral_prior`); 0: none.
    pub lateral_prior: f64,
    /// Robust mode's Geman-McClure scale over sigma in registrations with plane terms
    /// (`Robust::kernel_scale`).
    pub plane_kernel_scale: f64,
    /// Robust mode's cycle stop: a registration with plane terms also stops when its iterate
    /// comes back to one of its last iterates (`Robust::cycle_stop`).
    pub cycle_stop: bool,
    /// `reference` or `robust`.
    pub degeneracy: DegeneracyMode,
    /// ICP's work budget per frame in the core's work units (`FrameReport::work`); absent:
    /// none, the reference's behaviour.
    pub work_budget: Option<u64>,
}

/// Capacities of the core's buffers (see `kiss_odom_core::Capacities`). Each one left out is
/// sized from the configuration (`Capacities::sized_for`: the range, voxel size and `N_max`,
/// for a sensor of up to [`SCAN_POINTS`] points a sweep), so that the map does not fill.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Caps {
    /// Input points considered per scan.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scan_points: Option<usize>,
    /// Merge cloud points.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub merge_points: Option<usize>,
    /// Registration cloud points.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub source_points: Option<usize>,
    /// Map voxels.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub map_voxels: Option<usize>,
    /// Map points.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub map_points: Option<usize>,
}

/// Points per sweep the capacities sized from the configuration hold (an OS1-128 at 2048
/// columns); a larger sweep is truncated with a warning.
pub const SCAN_POINTS: usize = 262_144;

/// How the core runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Runtime {
    /// f64 or f32.
    pub scalar: Scalar,
    /// Map point storage.
    pub map_storage: Storage,
    /// Worker threads for the correspondence search (0 = all cores). Results do not depend on
    /// it.
    pub threads: usize,
    /// Bytes the core's state may grow to when no capacity is given (see
    /// `kiss_odom_drive::growth`); absent: a quarter of the machine's memory.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub memory_limit: Option<u64>,
}

/// All settings of a run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Settings {
    /// The preset.
    pub pipeline: Pipeline,
    /// Sensor data.
    pub data: Data,
    /// Map.
    pub mapping: Mapping,
    /// Threshold.
    pub adaptive_threshold: Threshold,
    /// ICP.
    pub registration: Registration,
    /// Buffers.
    pub capacities: Caps,
    /// Execution.
    pub runtime: Runtime,
    /// The opt-in gyroscope prior (left out of the file when off with its defaults).
    #[serde(skip_serializing_if = "Imu::is_default")]
    pub imu: Imu,
    /// How sensor packets become frames (left out of the file with its defaults).
    #[serde(skip_serializing_if = "Input::is_default")]
    pub input: Input,
    /// What the outputs hold (left out of the file with its defaults).
    #[serde(skip_serializing_if = "Output::is_default")]
    pub output: Output,
}

impl Default for Data {
    fn default() -> Self {
        Self {
            max_range: 100.0,
            min_range: 0.0,
            deskew: true,
            redeskew: false,
        }
    }
}

impl Default for Mapping {
    fn default() -> Self {
        Self {
            voxel_size: None,
            max_points_per_voxel: 20,
            alpha: 0.5,
            beta: 1.5,
            reference_order: true,
            desired_source_points: 0,
        }
    }
}

impl Default for Threshold {
    fn default() -> Self {
        Self {
            initial_threshold: 2.0,
            min_motion_th: 0.1,
        }
    }
}

impl Default for Registration {
    fn default() -> Self {
        Self {
            max_num_iterations: 500,
            convergence_criterion: 1e-4,
            kernel_scale: None,
            max_correspondence_factor: 3.0,
            degeneracy_ratio: Config::<f64>::new(100.0).degeneracy_ratio,
            plane_gate: Robust::<f64>::new().plane_gate,
            prediction_prior: Robust::<f64>::new().prediction_prior,
            lateral_prior: Robust::<f64>::new().lateral_prior,
            plane_kernel_scale: Robust::<f64>::new().kernel_scale,
            cycle_stop: Robust::<f64>::new().cycle_stop,
            degeneracy: DegeneracyMode::Reference,
            work_budget: None,
        }
    }
}

impl From<Capacities> for Caps {
    fn from(c: Capacities) -> Self {
        Self {
            scan_points: Some(c.scan_points),
            merge_points: Some(c.merge_points),
            source_points: Some(c.source_points),
            map_voxels: Some(c.map_voxels),
            map_points: Some(c.map_points),
        }
    }
}

impl Default for Runtime {
    fn default() -> Self {
        Self {
            scalar: Scalar::F64,
            map_storage: Storage::Exact,
            threads: 0,
            memory_limit: None,
        }
    }
}

impl Settings {
    /// The defaults of `preset`: every pipeline setting from the core's configuration of that
    /// preset (`Config::new` or `Config::accurate`), the voxel size left to follow the range.
    pub fn preset(preset: PresetName) -> Self {
        let mut s = Self::default();
        s.pipeline.preset = preset;
        let c = s.core_defaults();
        s.data.redeskew = c.redeskew;
        s.mapping.max_points_per_voxel = c.max_points_per_voxel;
        s.mapping.alpha = c.alpha;
        s.mapping.beta = c.beta;
        s.mapping.reference_order = c.reference_order;
        s.mapping.desired_source_points = c.desired_source_points;
        s.adaptive_threshold.initial_threshold = c.initial_threshold;
        s.adaptive_threshold.min_motion_th = c.min_motion_threshold;
        let r = &mut s.registration;
        r.max_num_iterations = c.max_iterations;
        r.convergence_criterion = c.convergence_criterion;
        r.max_correspondence_factor = c.max_correspondence_factor;
        r.degeneracy_ratio = c.degeneracy_ratio;
        r.plane_gate = c.robust.plane_gate;
        r.prediction_prior = c.robust.prediction_prior;
        r.lateral_prior = c.robust.lateral_prior;
        r.plane_kernel_scale = c.robust.kernel_scale;
        r.cycle_stop = c.robust.cycle_stop;
        r.degeneracy = c.degeneracy.into();
        s
    }

    /// The core's configuration of this preset at this range.
    fn core_defaults(&self) -> Config<f64> {
        match self.pipeline.preset {
            PresetName::Default => Config::new(self.data.max_range),
            PresetName::Accurate => Config::accurate(self.data.max_range),
        }
    }

    /// Reads a settings file: kiss-icp's YAML when its name ends in `.yaml` or `.yml`, else
    /// TOML (the layout of `config.toml`). Unknown keys are errors (a typo must not silently
    /// fall back).
    pub fn load(path: &Path) -> Result<Self> {
        Self::load_as(path, None)
    }

    /// [`Self::load`], over the defaults of `preset` when given (replacing the file's
    /// `[pipeline] preset`), else of the file's preset.
    pub fn load_as(path: &Path, preset: Option<PresetName>) -> Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
        let yaml = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("yaml") || e.eq_ignore_ascii_case("yml"));
        if yaml {
            let base = Self::preset(preset.unwrap_or_default());
            return Self::from_kiss_icp_yaml_over(&text, base).with_context(|| {
                format!("{}: invalid kiss-icp YAML configuration", path.display())
            });
        }
        let context = || {
            format!(
                "{}: invalid configuration (read as TOML; a kiss-icp YAML file needs a .yaml \
                 or .yml name)",
                path.display()
            )
        };
        // Read once as settings for the errors' line numbers, then over the preset's defaults.
        let file: Settings = toml::from_str(&text).with_context(context)?;
        let table: toml::Table = toml::from_str(&text).with_context(context)?;
        Self::preset(preset.unwrap_or(file.pipeline.preset))
            .overlaid(table)
            .with_context(context)
    }

    /// These settings with every value `over` gives in its place (sections merged key by key).
    fn overlaid(&self, over: toml::Table) -> Result<Self> {
        fn merge(base: &mut toml::Table, over: toml::Table) {
            for (key, value) in over {
                match (base.get_mut(&key), value) {
                    (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
                    (_, value) => {
                        base.insert(key, value);
                    }
                }
            }
        }
        let mut base = toml::Table::try_from(self)?;
        merge(&mut base, over);
        let mut s: Settings = base.try_into()?;
        s.pipeline.preset = self.pipeline.preset;
        Ok(s)
    }

    /// Settings from kiss-icp's YAML configuration (`kiss_icp.config.load_config`'s file), read
    /// as the Python package reads it: its sections are ours (`data`, `mapping`,
    /// `adaptive_threshold`, `registration`, plus our `capacities` and `runtime`), with
    /// `registration.max_num_threads` as `runtime.threads`, `out_dir` (its pipeline's) ignored,
    /// `null` as not given, and the voxel size made explicit at `max_range / 100` when not given,
    /// as kiss-icp does. `adaptive_threshold.fixed_threshold` is refused: the core always adapts.
    pub fn from_kiss_icp_yaml(text: &str) -> Result<Self> {
        Self::from_kiss_icp_yaml_over(text, Settings::default())
    }

    /// [`Self::from_kiss_icp_yaml`] over `base` (a preset's defaults): each section's keys
    /// replace `base`'s.
    fn from_kiss_icp_yaml_over(text: &str, base: Settings) -> Result<Self> {
        use serde_yaml_ng::Value;
        let doc: Value = serde_yaml_ng::from_str(text)?;
        let mut s = base;
        let top = match doc {
            Value::Null => return Ok(s.with_explicit_voxel()),
            Value::Mapping(m) => m,
            _ => bail!("expected sections (data:, mapping:, ...) at the top"),
        };
        // `null` is kiss-icp's "not given" (pydantic's None), except where it means "derive".
        let given = |section: &str, value: &Value| -> Result<Value> {
            let Value::Mapping(m) = value else {
                bail!("`{section}` is not a mapping of settings");
            };
            let kept = m
                .iter()
                .filter(|(k, v)| !v.is_null() || k.as_str() == Some("voxel_size"))
                .map(|(k, v)| (k.clone(), v.clone()));
            Ok(Value::Mapping(kept.collect()))
        };
        fn section<T: serde::de::DeserializeOwned + Serialize>(
            name: &str,
            base: &T,
            v: Value,
        ) -> Result<T> {
            let mut merged = serde_yaml_ng::to_value(base)?;
            if let (Value::Mapping(m), Value::Mapping(over)) = (&mut merged, v) {
                m.extend(over);
            }
            serde_yaml_ng::from_value(merged).with_context(|| format!("`{name}`"))
        }
        let mut threads = None;
        for (key, value) in &top {
            let name = key.as_str().unwrap_or_default();
            if value.is_null() {
                continue;
            }
            match name {
                "out_dir" => {}
                "data" => s.data = section(name, &s.data, given(name, value)?)?,
                "mapping" => s.mapping = section(name, &s.mapping, given(name, value)?)?,
                "adaptive_threshold" => {
                    let mut v = given(name, value)?;
                    if let Some(t) = v.as_mapping_mut().and_then(|m| m.remove("fixed_threshold")) {
                        bail!(
                            "adaptive_threshold.fixed_threshold = {}: not supported, kiss-odom's \
                             core always adapts the threshold (set initial_threshold instead)",
                            serde_yaml_ng::to_string(&t).unwrap_or_default().trim()
                        );
                    }
                    s.adaptive_threshold = section(name, &s.adaptive_threshold, v)?;
                }
                "registration" => {
                    let mut v = given(name, value)?;
                    threads = v.as_mapping_mut().and_then(|m| m.remove("max_num_threads"));
                    s.registration = section(name, &s.registration, v)?;
                }
                "capacities" => s.capacities = section(name, &s.capacities, given(name, value)?)?,
                "runtime" => s.runtime = section(name, &s.runtime, given(name, value)?)?,
                _ => bail!(
                    "unknown section `{}` (kiss-icp's: data, mapping, adaptive_threshold, \
                     registration, out_dir; kiss-odom's: capacities, runtime)",
                    serde_yaml_ng::to_string(key).unwrap_or_default().trim()
                ),
            }
        }
        let runtime_threads = top
            .get("runtime")
            .and_then(|r| r.get("threads"))
            .is_some_and(|t| !t.is_null());
        if let (Some(t), false) = (threads, runtime_threads) {
            s.runtime.threads = serde_yaml_ng::from_value(t)
                .context("`registration.max_num_threads`")
                .map(|t: Option<usize>| t.unwrap_or(0))?;
        }
        Ok(s.with_explicit_voxel())
    }

    /// These settings with the voxel size given (the preset's when it was not).
    fn with_explicit_voxel(mut self) -> Self {
        self.mapping.voxel_size = Some(self.voxel_size());
        self
    }

    /// The TOML text of these settings, with the voxel size made explicit, and the capacities
    /// too when they were given (left out, they grow: see [`Self::memory_limit`]); an omitted
    /// kernel scale stays omitted.
    pub fn to_toml(&self) -> Result<String> {
        let mut s = self.clone();
        s.mapping.voxel_size = Some(self.voxel_size());
        if !self.grows() {
            s.capacities = self.caps().into();
        }
        Ok(toml::to_string(&s)?)
    }

    /// Whether the core's storage grows: no capacity is given, so they start sized from the
    /// configuration and a frame that would overfill one moves the core into larger storage.
    pub fn grows(&self) -> bool {
        self.capacities == Caps::default()
    }

    /// The bytes the core's state may grow to: `[runtime] memory_limit`, or a quarter of the
    /// machine's memory; `None` when capacities are given, which never grow.
    pub fn memory_limit(&self) -> Option<u64> {
        self.grows().then(|| {
            self.runtime
                .memory_limit
                .unwrap_or_else(crate::growth::default_limit)
        })
    }

    /// `v`: explicit, or the preset's: `max_range / 100` as in the paper (`accurate`:
    /// `max_range / 200`).
    pub fn voxel_size(&self) -> f64 {
        self.mapping
            .voxel_size
            .unwrap_or_else(|| self.core_defaults().voxel_size)
    }

    /// The Geman-McClure scale over sigma of the reference's registration: explicit, or 1 as
    /// kiss-icp (robust mode's plane terms use `PLANE_KERNEL_SCALE`).
    pub fn kernel_scale(&self) -> f64 {
        self.registration
            .kernel_scale
            .unwrap_or_else(|| Config::new(self.data.max_range).kernel_scale)
    }

    /// The capacities given, the rest sized from the configuration; room for plane terms in
    /// robust mode only.
    fn caps(&self) -> Capacities {
        let c = &self.capacities;
        let mut cfg = Config::<f64>::new(self.data.max_range);
        cfg.voxel_size = self.voxel_size();
        cfg.beta = self.mapping.beta;
        cfg.max_points_per_voxel = self.mapping.max_points_per_voxel;
        let sized = Capacities::sized_for(&cfg, c.scan_points.unwrap_or(SCAN_POINTS));
        Capacities {
            scan_points: sized.scan_points,
            merge_points: c.merge_points.unwrap_or(sized.merge_points),
            source_points: c.source_points.unwrap_or(sized.source_points),
            map_voxels: c.map_voxels.unwrap_or(sized.map_voxels),
            map_points: c.map_points.unwrap_or(sized.map_points),
            plane_terms: self.registration.degeneracy == DegeneracyMode::Robust,
        }
    }

    /// The core's configuration in scalar `T`; [`Self::validate`] names the setting at fault.
    pub fn core_config<T: Real>(&self) -> Result<Config<T>> {
        let mut c = Config::<T>::new(T::of(self.data.max_range));
        c.min_range = T::of(self.data.min_range);
        c.voxel_size = T::of(self.voxel_size());
        c.alpha = T::of(self.mapping.alpha);
        c.beta = T::of(self.mapping.beta);
        c.reference_order = self.mapping.reference_order;
        c.max_points_per_voxel = self.mapping.max_points_per_voxel;
        c.desired_source_points = self.mapping.desired_source_points;
        c.initial_threshold = T::of(self.adaptive_threshold.initial_threshold);
        c.min_motion_threshold = T::of(self.adaptive_threshold.min_motion_th);
        c.convergence_criterion = T::of(self.registration.convergence_criterion);
        c.max_iterations = self.registration.max_num_iterations;
        c.deskew = self.data.deskew;
        c.redeskew = self.data.redeskew;
        c.kernel_scale = T::of(self.kernel_scale());
        c.max_correspondence_factor = T::of(self.registration.max_correspondence_factor);
        c.degeneracy_ratio = T::of(self.registration.degeneracy_ratio);
        c.robust = Robust {
            plane_gate: T::of(self.registration.plane_gate),
            prediction_prior: T::of(self.registration.prediction_prior),
            lateral_prior: T::of(self.registration.lateral_prior),
            kernel_scale: T::of(self.registration.plane_kernel_scale),
            cycle_stop: self.registration.cycle_stop,
        };
        c.degeneracy = self.registration.degeneracy.into();
        c.work_budget = self.registration.work_budget;
        if let Err(e) = c.validate() {
            bail!("invalid configuration: {e}");
        }
        Ok(c)
    }

    /// The core's capacities.
    pub fn capacities(&self) -> Result<Capacities> {
        let caps = self.caps();
        if let Err(e) = caps.validate() {
            bail!("invalid capacities: {e}");
        }
        Ok(caps)
    }

    /// What the core would refuse in these settings, if anything.
    fn fault(&self) -> Option<anyhow::Error> {
        self.core_config::<f64>()
            .err()
            .or_else(|| self.capacities().err())
            .or_else(|| self.imu.core::<f64>().err())
    }

    /// Checks every value the core will get. The error names the setting at fault and its
    /// value: the one that, put back to its default, makes the settings valid (several when
    /// more than one would).
    pub fn validate(&self) -> Result<()> {
        self.refuse_non_finite()?;
        if let Some(e) = self.input.fault().or_else(|| self.output.fault()) {
            bail!("{e}");
        }
        let Some(e) = self.fault() else {
            return Ok(());
        };
        let defaults = Settings::preset(self.pipeline.preset);
        let culprits: Vec<String> = fields()
            .iter()
            .filter(|f| {
                let mut fixed = self.clone();
                (f.reset)(&mut fixed, &defaults);
                f.show(&fixed) != f.show(self) && fixed.fault().is_none()
            })
            .map(|f| format!("{} = {}", f.name, f.show(self)))
            .collect();
        if culprits.is_empty() {
            return Err(e);
        }
        Err(e.context(culprits.join(" or ")))
    }

    /// Refuses NaN and inf, naming each setting: they pass some of the core's range checks
    /// (`inf >= 1`), fail others with no name, and JSON has no way to write them.
    pub fn refuse_non_finite(&self) -> Result<()> {
        let non_finite: Vec<String> = fields()
            .iter()
            .filter(|f| matches!((f.value)(self), Some(toml::Value::Float(v)) if !v.is_finite()))
            .map(|f| format!("{} = {}", f.name, f.show(self)))
            .collect();
        if !non_finite.is_empty() {
            bail!("{}: not a finite number", non_finite.join(", "));
        }
        Ok(())
    }

    /// The pipeline settings away from their defaults that the reference's driver does not
    /// take (it takes the range, voxel size and deskewing; capacities, the degeneracy ratio and
    /// the plane gate are ours alone and do not change poses outside hold and robust mode, which
    /// `degeneracy` names).
    pub fn changed_beyond_reference(&self) -> Vec<&'static str> {
        // A kernel scale written out (as `run` does) is not a change when it is the default's.
        let resolved = |s: &Settings| {
            let mut s = s.clone();
            s.registration.kernel_scale = Some(s.kernel_scale());
            s
        };
        let (this, defaults) = (resolved(self), resolved(&Settings::default()));
        fields()
            .iter()
            .filter(|f| !f.reference_takes && f.show(&this) != f.show(&defaults))
            .map(|f| f.name)
            .collect()
    }

    /// Threads to use: 0 means all cores, and a count above the machine's cores is capped to
    /// them (more only contend, and a huge count would take minutes to start).
    pub fn threads(&self) -> usize {
        let cores = cores();
        match self.runtime.threads {
            0 => cores,
            n => n.min(cores),
        }
    }

    /// The robust mode's settings given other values than their defaults while the run is in
    /// reference mode, which does not use them: one warning each.
    pub fn unused_warnings(&self) -> Vec<String> {
        if self.registration.degeneracy != DegeneracyMode::Reference {
            return Vec::new();
        }
        let defaults = Settings::default();
        fields()
            .iter()
            .filter(|f| ROBUST_ONLY.contains(&f.name) && f.show(self) != f.show(&defaults))
            .map(|f| {
                format!(
                    "{} = {} not used: it acts in robust mode only (registration.degeneracy = \
                     robust, or --preset accurate), and this run is in reference mode",
                    f.name,
                    f.show(self)
                )
            })
            .collect()
    }

    /// The warning to print when [`Self::threads`] capped the count asked for.
    pub fn threads_warning(&self) -> Option<String> {
        let (asked, cores) = (self.runtime.threads, cores());
        (asked > cores).then(|| {
            format!("{asked} threads asked for, but the machine has {cores} cores: using {cores}")
        })
    }
}

fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// A setting by its TOML name: how to print its value, how to put back its default, and
/// whether the reference's driver takes it (or it does not change poses).
struct Field {
    name: &'static str,
    /// The value as TOML writes it (`nan` and `inf` included); `None` when not given.
    value: fn(&Settings) -> Option<toml::Value>,
    reset: fn(&mut Settings, &Settings),
    reference_takes: bool,
}

impl Field {
    /// The value as an error message names it.
    fn show(&self, s: &Settings) -> String {
        (self.value)(s).map_or_else(|| "none".into(), |v| v.to_string())
    }
}

macro_rules! field {
    ($section:ident . $name:ident, $takes:expr) => {
        Field {
            name: concat!(stringify!($section), ".", stringify!($name)),
            value: |s| toml::Value::try_from(&s.$section.$name).ok(),
            reset: |s, d| s.$section.$name = d.$section.$name.clone(),
            reference_takes: $takes,
        }
    };
}

/// The settings only robust mode reads.
const ROBUST_ONLY: [&str; 5] = [
    "registration.plane_gate",
    "registration.prediction_prior",
    "registration.lateral_prior",
    "registration.plane_kernel_scale",
    "registration.cycle_stop",
];

/// Every setting the core gets.
fn fields() -> [Field; 31] {
    [
        field!(data.max_range, true),
        field!(data.min_range, true),
        field!(mapping.voxel_size, true),
        field!(mapping.max_points_per_voxel, false),
        field!(mapping.alpha, false),
        field!(mapping.beta, false),
        field!(mapping.reference_order, false),
        field!(mapping.desired_source_points, false),
        field!(adaptive_threshold.initial_threshold, false),
        field!(adaptive_threshold.min_motion_th, false),
        field!(registration.max_num_iterations, false),
        field!(registration.convergence_criterion, false),
        field!(registration.kernel_scale, false),
        field!(registration.max_correspondence_factor, false),
        field!(registration.degeneracy_ratio, true),
        field!(registration.plane_gate, true),
        field!(registration.prediction_prior, true),
        field!(registration.lateral_prior, true),
        field!(registration.plane_kernel_scale, true),
        field!(registration.cycle_stop, true),
        field!(registration.degeneracy, false),
        field!(registration.work_budget, false),
        field!(capacities.scan_points, true),
        field!(capacities.merge_points, true),
        field!(capacities.source_points, true),
        field!(capacities.map_voxels, true),
        field!(capacities.map_points, true),
        field!(imu.enabled, false),
        field!(imu.time_offset, true),
        field!(imu.bias_gain, true),
        field!(imu.max_gap, true),
    ]
}

mod imu;
mod run;
mod set;
pub use imu::Imu;
pub use run::{Input, Output, PoseTime};
pub use set::parse_size;

#[cfg(test)]
mod tests;
