//! A co-simulation instance of a loaded FMU and its saved states.
//!
//! Call sequence (co-simulation, the same for FMI 2.0 and FMI 3.0):
//!
//! ```text
//!   Fmu::instantiate ─▶ set_* (parameters, start values)
//!   setup_experiment(t0, stop) ─▶ enter_initialization_mode ─▶ set_*/get_* ─▶ exit_initialization_mode
//!   repeat: set_* (inputs) ─▶ do_step(t, h) ─▶ get_* (outputs)      t ← t + h
//!           get_state / set_state where canGetAndSetFMUstate, serialize where canSerializeFMUstate
//!   terminate ─▶ drop (fmi2FreeInstance / fmi3FreeInstance)
//! ```
//!
//! Each method calls the function of the FMU's version: `set_real` is `fmi2SetReal` or
//! `fmi3SetFloat64`, and so on. FMI 3.0 has no `fmi2SetupExperiment`: there
//! [`Instance::setup_experiment`] only remembers the start and stop times, which
//! [`Instance::enter_initialization_mode`] passes to `fmi3EnterInitializationMode`. An
//! FMI 3.0 instance is made without event mode and without early return, so after
//! initialization it is in step mode, as an FMI 2.0 one is.
//!
//! Every call is made under the instance's mutex, checks the status returned, and after
//! an `fmi2Fatal` or `fmi3Fatal` no further call (not even the free) reaches the FMU.

use std::ffi::{c_char, CString};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex, MutexGuard};

use super::description::VarKind;
use super::fmi2::{self, CallbackFunctions, Component, LogTarget, Status};
use super::fmi3;
use super::loaded::{Api, Loaded};
use super::value::{Value, MAX_VALUE_BYTES};
use super::FmuError;

/// Largest serialized state accepted from an FMU [bytes]: 1 GiB, so a corrupt size
/// cannot make the allocation abort the process.
pub const MAX_STATE_BYTES: usize = 1 << 30;

/// The instance proper, shared by the [`Instance`] handle and its [`FmuState`]s so that
/// the component outlives every state made from it (and the library outlives both).
struct Core {
    shared: Arc<Loaded>,
    name: String,
    logging: bool,
    inner: Mutex<Inner>,
    /// `Box::into_raw` of the callback table given to `fmi2Instantiate` (the FMU may
    /// keep the pointer; null for FMI 3.0, which has none) and of the logger's target
    /// (the instance environment of both versions); freed after the instance is.
    callbacks: *mut CallbackFunctions,
    log: *mut LogTarget,
}

/// What the mutex guards.
struct Inner {
    component: Component,
    /// An earlier call returned `fmi2Fatal`: call nothing more.
    fatal: bool,
    /// The last communication point reached [s] (for messages).
    time: Option<f64>,
    /// FMI 3.0: the start time [s] and stop time [s] given to `setup_experiment`, for
    /// `fmi3EnterInitializationMode` (start 0, no stop, until then).
    experiment: (f64, Option<f64>),
}

// SAFETY: every use of the component goes through `inner`'s mutex, so the FMU is never
// called on one instance from two threads at once (FMI 2.0 forbids concurrent calls on an
// instance, not calls from different threads in turn; dsmcosim makes none concurrently
// anyway). The callback and log pointers are written once before the first call and read
// by the FMU only inside calls made under the mutex.
unsafe impl Send for Core {}
// SAFETY: as for `Send`: shared access only ever reaches the FMU under the mutex.
unsafe impl Sync for Core {}

impl Drop for Core {
    fn drop(&mut self) {
        let inner = self.inner.get_mut().unwrap_or_else(|e| e.into_inner());
        if !inner.fatal {
            // SAFETY: the component is live (states are gone: each holds this Core).
            match self.shared.api {
                Api::Fmi2(f) => unsafe { (f.free_instance)(inner.component) },
                Api::Fmi3(f) => unsafe { (f.free_instance)(inner.component) },
            }
        }
        // SAFETY: made by `Box::into_raw` in `Instance::new`, freed once here, after the
        // FMU has let go of them (or, after a fatal status, is never called again).
        unsafe {
            if !self.callbacks.is_null() {
                drop(Box::from_raw(self.callbacks));
            }
            drop(Box::from_raw(self.log));
        }
        self.shared.instances.fetch_sub(1, Ordering::SeqCst);
    }
}

/// How [`Instance::do_step`] ended.
#[derive(Debug, Clone, PartialEq)]
pub enum StepEnd {
    /// The step reached its end.
    Completed,
    /// The FMU asked to end the simulation: it reached `reached` [s] (the step's end, or
    /// an earlier time it could not go past) and cannot be stepped further.
    Stopped {
        /// The last time the FMU completed [s], between the step's start and end.
        reached: f64,
        /// How it asked, in the FMI's words.
        reason: String,
    },
}

/// One co-simulation instance of an [`super::Fmu`]. Freed (`fmi2FreeInstance` or
/// `fmi3FreeInstance`) when it and every [`FmuState`] made from it are dropped.
pub struct Instance {
    core: Arc<Core>,
}

impl std::fmt::Debug for Instance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Instance")
            .field("fmu", &self.core.shared.name)
            .field("name", &self.core.name)
            .finish_non_exhaustive()
    }
}

/// A saved FMU state (`fmi2FMUstate`, `fmi3FMUState`) of one instance; freed with
/// `fmi2FreeFMUstate` or `fmi3FreeFMUState` on drop. It keeps its instance alive, so
/// dropping the [`Instance`] first is fine.
pub struct FmuState {
    state: fmi2::State,
    core: Arc<Core>,
}

impl std::fmt::Debug for FmuState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FmuState")
            .field("instance", &self.core.name)
            .finish_non_exhaustive()
    }
}

// SAFETY: the state pointer is only passed to the FMU under its instance's mutex (in
// `set_state`, `serialize_state` and `drop`).
unsafe impl Send for FmuState {}
// SAFETY: `&FmuState` only reads the pointer, and uses it under the mutex.
unsafe impl Sync for FmuState {}

impl Drop for FmuState {
    fn drop(&mut self) {
        let inner = self.core.lock();
        if inner.fatal || self.state.is_null() {
            return;
        }
        // Every state is made under canGetAndSetFMUstate, so `free` is resolved. The two
        // versions' free functions have the same C type.
        let free = match self.core.shared.api {
            Api::Fmi2(f) => f.state.map(|(_, _, free)| free),
            Api::Fmi3(f) => f.state.map(|(_, _, free)| free),
        };
        if let Some(free) = free {
            // SAFETY: the state came from this component and is freed once.
            unsafe { free(inner.component, &mut self.state) };
        }
    }
}

impl Core {
    fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn fmi3(&self) -> bool {
        matches!(self.shared.api, Api::Fmi3(_))
    }

    /// The C name of `status` in the FMU's version (`fmi2Error`, `fmi3Error`).
    fn status_name(&self, status: Status) -> &'static str {
        if self.fmi3() {
            fmi3::status_name(status)
        } else {
            fmi2::status_name(status)
        }
    }

    /// Makes one FMI call under the mutex and checks its status; `time` is the time the
    /// message names (`None`: the last communication point). On success the lock is
    /// handed back, so a caller can record what the call changed (the time) atomically.
    /// The status codes OK, Warning, Discard, Error and Fatal are the same numbers in
    /// FMI 2.0 and 3.0; `fmi2Pending` (5) has no FMI 3.0 counterpart and is an error.
    fn call(
        &self,
        function: &'static str,
        time: Option<f64>,
        f: impl FnOnce(Component) -> Status,
    ) -> Result<MutexGuard<'_, Inner>, FmuError> {
        let (inner, status) = self.call_status(function, time, f)?;
        if status == fmi2::DISCARD {
            return Err(FmuError::Status {
                fmu: self.shared.name.clone(),
                function,
                time: time.or(inner.time),
                status: self.status_name(status),
            });
        }
        Ok(inner)
    }

    /// [`Core::call`], but a discarded call (`fmi2Discard`, `fmi3Discard`) is handed back
    /// with its status rather than refused: a step's caller asks the FMU why.
    fn call_status(
        &self,
        function: &'static str,
        time: Option<f64>,
        f: impl FnOnce(Component) -> Status,
    ) -> Result<(MutexGuard<'_, Inner>, Status), FmuError> {
        let mut inner = self.lock();
        if inner.fatal {
            return Err(FmuError::Unusable {
                fmu: self.shared.name.clone(),
                function,
                status: self.status_name(fmi2::FATAL),
            });
        }
        let status = f(inner.component);
        let time = time.or(inner.time);
        match status {
            fmi2::OK | fmi2::DISCARD => Ok((inner, status)),
            fmi2::WARNING => {
                if self.logging {
                    use std::io::Write;
                    let _ = writeln!(
                        std::io::stderr(),
                        "[{}] {function} returned {}",
                        self.name,
                        self.status_name(status)
                    );
                }
                Ok((inner, status))
            }
            other => {
                if other == fmi2::FATAL {
                    inner.fatal = true;
                }
                Err(FmuError::Status {
                    fmu: self.shared.name.clone(),
                    function,
                    time,
                    status: self.status_name(other),
                })
            }
        }
    }
}

impl Instance {
    /// Instantiates for co-simulation, not visible: `fmi2Instantiate` with the FMU's GUID
    /// and resource URI, or `fmi3InstantiateCoSimulation` with its instantiation token
    /// and resource path, without event mode, early return or intermediate updates. The
    /// caller has counted the instance in `shared.instances`.
    pub(crate) fn new(
        shared: Arc<Loaded>,
        instance_name: &str,
        logging: bool,
    ) -> Result<Instance, FmuError> {
        let uncount = |shared: &Loaded| {
            shared.instances.fetch_sub(1, Ordering::SeqCst);
        };
        let c_string = |what, s: &str| {
            CString::new(s).map_err(|_| FmuError::NulByte {
                what,
                value: s.replace('\0', "\\0"),
            })
        };
        let (name, guid) = match (
            c_string("instance name", instance_name),
            c_string("guid", &shared.description.guid),
        ) {
            (Ok(n), Ok(g)) => (n, g),
            (Err(e), _) | (_, Err(e)) => {
                uncount(&shared);
                return Err(e);
            }
        };
        let log = Box::into_raw(Box::new(LogTarget {
            instance: instance_name.to_string(),
            on: logging,
            fmu: shared.name.clone(),
            log: Arc::clone(&shared.log),
        }));
        let (component, callbacks, function) = match shared.api {
            Api::Fmi2(f) => {
                let callbacks = Box::into_raw(Box::new(fmi2::callbacks(log)));
                // SAFETY: all pointers are valid NUL-terminated strings or live boxes; the
                // boxes live until after fmi2FreeInstance (Core::drop).
                let component = unsafe {
                    (f.instantiate)(
                        name.as_ptr(),
                        fmi2::CO_SIMULATION,
                        guid.as_ptr(),
                        shared.resource_uri.as_ptr(),
                        callbacks,
                        0,
                        i32::from(logging),
                    )
                };
                (component, callbacks, "fmi2Instantiate")
            }
            Api::Fmi3(f) => {
                // SAFETY: the strings are NUL-terminated; no required intermediate
                // variables (null, 0); `log` is a live box until after fmi3FreeInstance;
                // the intermediate-update callback is null, as event mode and early
                // return are off.
                let component = unsafe {
                    (f.instantiate)(
                        name.as_ptr(),
                        guid.as_ptr(),
                        shared.resource_path.as_ptr(),
                        0,
                        u8::from(logging),
                        0,
                        0,
                        std::ptr::null(),
                        0,
                        log.cast(),
                        Some(fmi3::log_message),
                        std::ptr::null(),
                    )
                };
                (
                    component,
                    std::ptr::null_mut(),
                    "fmi3InstantiateCoSimulation",
                )
            }
        };
        if component.is_null() {
            // SAFETY: the FMU made no instance, so nothing refers to the boxes.
            unsafe {
                if !callbacks.is_null() {
                    drop(Box::from_raw(callbacks));
                }
                drop(Box::from_raw(log));
            }
            uncount(&shared);
            return Err(FmuError::NullInstance {
                fmu: shared.name.clone(),
                function,
                instance: instance_name.to_string(),
            });
        }
        Ok(Instance {
            core: Arc::new(Core {
                shared,
                name: instance_name.to_string(),
                logging,
                inner: Mutex::new(Inner {
                    component,
                    fatal: false,
                    time: None,
                    experiment: (0.0, None),
                }),
                callbacks,
                log,
            }),
        })
    }

    /// The instance's name.
    pub fn name(&self) -> &str {
        &self.core.name
    }

    /// The FMU's name.
    pub fn fmu_name(&self) -> &str {
        &self.core.shared.name
    }

    /// The last communication point reached [s]: the start time after
    /// [`Instance::setup_experiment`], `t + h` after each successful [`Instance::do_step`].
    pub fn time(&self) -> Option<f64> {
        self.core.lock().time
    }

    /// The experiment from `start` [s] to `stop` [s] (if defined), tolerance undefined:
    /// `fmi2SetupExperiment` in FMI 2.0; in FMI 3.0, which has no such call, the times
    /// are kept for [`Instance::enter_initialization_mode`].
    pub fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Result<(), FmuError> {
        let f = match self.core.shared.api {
            Api::Fmi2(f) => f,
            Api::Fmi3(_) => {
                let mut inner = self.core.lock();
                inner.experiment = (start, stop);
                inner.time = Some(start);
                return Ok(());
            }
        };
        let (defined, stop_time) = (i32::from(stop.is_some()), stop.unwrap_or(0.0));
        let mut inner = self.core.call("fmi2SetupExperiment", Some(start), |c| {
            // SAFETY: a live component; plain values.
            unsafe { (f.setup_experiment)(c, 0, 0.0, start, defined, stop_time) }
        })?;
        inner.time = Some(start);
        Ok(())
    }

    /// `fmi2EnterInitializationMode`, or `fmi3EnterInitializationMode` with the start and
    /// stop times of [`Instance::setup_experiment`] (start 0 and no stop without it).
    pub fn enter_initialization_mode(&mut self) -> Result<(), FmuError> {
        match self.core.shared.api {
            Api::Fmi2(f) => self.core.call("fmi2EnterInitializationMode", None, |c| {
                // SAFETY: a live component.
                unsafe { (f.enter_initialization_mode)(c) }
            }),
            Api::Fmi3(f) => {
                let (start, stop) = self.core.lock().experiment;
                let (defined, stop_time) = (u8::from(stop.is_some()), stop.unwrap_or(0.0));
                self.core
                    .call("fmi3EnterInitializationMode", Some(start), |c| {
                        // SAFETY: a live instance; plain values.
                        unsafe {
                            (f.enter_initialization_mode)(c, 0, 0.0, start, defined, stop_time)
                        }
                    })
                    .map(|mut inner| {
                        inner.time = Some(start);
                        inner
                    })
            }
        }
        .map(drop)
    }

    /// `fmi2ExitInitializationMode` or `fmi3ExitInitializationMode` (to step mode).
    pub fn exit_initialization_mode(&mut self) -> Result<(), FmuError> {
        let (function, call) = match self.core.shared.api {
            Api::Fmi2(f) => ("fmi2ExitInitializationMode", f.exit_initialization_mode),
            Api::Fmi3(f) => ("fmi3ExitInitializationMode", f.exit_initialization_mode),
        };
        self.core
            .call(function, None, |c| {
                // SAFETY: a live component.
                unsafe { call(c) }
            })
            .map(drop)
    }

    /// `fmi2Terminate` or `fmi3Terminate`.
    pub fn terminate(&mut self) -> Result<(), FmuError> {
        let (function, call) = match self.core.shared.api {
            Api::Fmi2(f) => ("fmi2Terminate", f.terminate),
            Api::Fmi3(f) => ("fmi3Terminate", f.terminate),
        };
        self.core
            .call(function, None, |c| {
                // SAFETY: a live component.
                unsafe { call(c) }
            })
            .map(drop)
    }

    /// `fmi2Reset` or `fmi3Reset`: back to the state right after instantiation.
    pub fn reset(&mut self) -> Result<(), FmuError> {
        let (function, call) = match self.core.shared.api {
            Api::Fmi2(f) => ("fmi2Reset", f.reset),
            Api::Fmi3(f) => ("fmi3Reset", f.reset),
        };
        let mut inner = self.core.call(function, None, |c| {
            // SAFETY: a live component.
            unsafe { call(c) }
        })?;
        inner.time = None;
        inner.experiment = (0.0, None);
        Ok(())
    }

    /// `fmi2DoStep` or `fmi3DoStep` from the communication point `t` [s] over `h` [s];
    /// inputs are held over the step as set. Prior states may still be restored
    /// afterwards (`noSetFMUStatePriorToCurrentPoint` = false).
    ///
    /// The FMU may ask to end the simulation ([`StepEnd::Stopped`]): in FMI 2.0 by
    /// returning `fmi2Discard` with `fmi2GetBooleanStatus(fmi2Terminated)` true (how far
    /// it got from `fmi2GetRealStatus(fmi2LastSuccessfulTime)`, `t` if it cannot say); in
    /// FMI 3.0 by setting `terminateSimulation` (with `fmi3OK`, `fmi3Warning` or
    /// `fmi3Discard`), or by returning early, which this importer does not allow and so
    /// cannot continue from (how far it got from `lastSuccessfulTime`). A discarded step
    /// without such a request is [`FmuError::Status`].
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<StepEnd, FmuError> {
        let f = match self.core.shared.api {
            Api::Fmi2(f) => {
                let (mut inner, status) = self.core.call_status("fmi2DoStep", Some(t), |c| {
                    // SAFETY: a live component; plain values.
                    unsafe { (f.do_step)(c, t, h, 0) }
                })?;
                if status != fmi2::DISCARD {
                    inner.time = Some(t + h);
                    return Ok(StepEnd::Completed);
                }
                let asked = f.status.and_then(|(real_status, boolean_status)| {
                    let (mut terminated, mut reached) = (0 as fmi2::Boolean, t);
                    // SAFETY: a live component; the out-parameters are live locals.
                    let asked = unsafe {
                        boolean_status(inner.component, fmi2::TERMINATED, &mut terminated)
                    } == fmi2::OK
                        && terminated != 0;
                    // SAFETY: as above.
                    let known = unsafe {
                        real_status(inner.component, fmi2::LAST_SUCCESSFUL_TIME, &mut reached)
                    } == fmi2::OK;
                    // A time the FMU cannot vouch for (NaN, outside the step) counts as
                    // the step's start.
                    let within = known && (t..=t + h).contains(&reached);
                    asked.then_some(if within { reached } else { t })
                });
                let Some(reached) = asked else {
                    return Err(FmuError::Status {
                        fmu: self.core.shared.name.clone(),
                        function: "fmi2DoStep",
                        time: Some(t),
                        status: fmi2::status_name(status),
                    });
                };
                inner.time = Some(reached);
                return Ok(StepEnd::Stopped {
                    reached,
                    reason: "fmi2DoStep returned fmi2Discard and fmi2Terminated is true".into(),
                });
            }
            Api::Fmi3(f) => f,
        };
        let (mut event, mut terminate, mut early, mut last) = (0u8, 0u8, 0u8, t);
        let (mut inner, status) = self.core.call_status("fmi3DoStep", Some(t), |c| {
            // SAFETY: a live instance; the out-parameters are live locals.
            unsafe {
                (f.do_step)(
                    c,
                    t,
                    h,
                    0,
                    &mut event,
                    &mut terminate,
                    &mut early,
                    &mut last,
                )
            }
        })?;
        // `eventHandlingNeeded` is only meaningful with event mode, which is off.
        let discarded = status == fmi3::DISCARD;
        let (reached, reason) = if terminate != 0 {
            // A completed step reached its end; a discarded or early one says how far.
            let reached = if discarded || early != 0 { last } else { t + h };
            let reason = format!(
                "fmi3DoStep returned {} with terminateSimulation = true",
                fmi3::status_name(status)
            );
            (reached, reason)
        } else if early != 0 && !discarded {
            let reason = format!(
                "fmi3DoStep returned early at t = {last} s, which this importer does not allow \
                 (earlyReturnAllowed = false), so it cannot go on"
            );
            (last, reason)
        } else if discarded {
            return Err(FmuError::Status {
                fmu: self.core.shared.name.clone(),
                function: "fmi3DoStep",
                time: Some(t),
                status: fmi3::status_name(status),
            });
        } else {
            inner.time = Some(t + h);
            return Ok(StepEnd::Completed);
        };
        // A time the FMU cannot vouch for (NaN, before the step) counts as the step's start.
        let reached = if (t..=t + h).contains(&reached) {
            reached
        } else {
            t
        };
        inner.time = Some(reached);
        Ok(StepEnd::Stopped { reached, reason })
    }

    /// `fmi2SetReal` or `fmi3SetFloat64`: `values[i]` to the variable `refs[i]`.
    pub fn set_real(&mut self, refs: &[u32], values: &[f64]) -> Result<(), FmuError> {
        let n = refs.len();
        match self.core.shared.api {
            Api::Fmi2(f) => {
                self.same_len("fmi2SetReal", n, values.len())?;
                self.core.call("fmi2SetReal", None, |c| {
                    // SAFETY: both slices hold `n` elements.
                    unsafe { (f.set_real)(c, refs.as_ptr(), n, values.as_ptr()) }
                })
            }
            Api::Fmi3(f) => {
                self.same_len("fmi3SetFloat64", n, values.len())?;
                self.core.call("fmi3SetFloat64", None, |c| {
                    // SAFETY: both slices hold `n` elements; scalars, so nValues = n.
                    unsafe { (f.set_float64)(c, refs.as_ptr(), n, values.as_ptr(), n) }
                })
            }
        }
        .map(drop)
    }

    /// `fmi2GetReal` or `fmi3GetFloat64`: the variable `refs[i]` into `values[i]`.
    pub fn get_real(&self, refs: &[u32], values: &mut [f64]) -> Result<(), FmuError> {
        let n = refs.len();
        match self.core.shared.api {
            Api::Fmi2(f) => {
                self.same_len("fmi2GetReal", n, values.len())?;
                self.core.call("fmi2GetReal", None, |c| {
                    // SAFETY: both slices hold `n` elements.
                    unsafe { (f.get_real)(c, refs.as_ptr(), n, values.as_mut_ptr()) }
                })
            }
            Api::Fmi3(f) => {
                self.same_len("fmi3GetFloat64", n, values.len())?;
                self.core.call("fmi3GetFloat64", None, |c| {
                    // SAFETY: both slices hold `n` elements; scalars, so nValues = n.
                    unsafe { (f.get_float64)(c, refs.as_ptr(), n, values.as_mut_ptr(), n) }
                })
            }
        }
        .map(drop)
    }

    /// `fmi2SetInteger`, or in FMI 3.0 `fmi3SetInt32`, with the references of
    /// enumerations set through `fmi3SetInt64` (their ABI type in FMI 3.0).
    pub fn set_integer(&mut self, refs: &[u32], values: &[i32]) -> Result<(), FmuError> {
        let f = match self.core.shared.api {
            Api::Fmi2(f) => {
                self.same_len("fmi2SetInteger", refs.len(), values.len())?;
                return self
                    .core
                    .call("fmi2SetInteger", None, |c| {
                        // SAFETY: both slices hold `refs.len()` elements.
                        unsafe { (f.set_integer)(c, refs.as_ptr(), refs.len(), values.as_ptr()) }
                    })
                    .map(drop);
            }
            Api::Fmi3(f) => f,
        };
        self.same_len("fmi3SetInt32", refs.len(), values.len())?;
        let (ints, enums) = self.split_enumerations(refs);
        if !ints.is_empty() {
            let r: Vec<u32> = ints.iter().map(|&i| refs[i]).collect();
            let v: Vec<i32> = ints.iter().map(|&i| values[i]).collect();
            drop(self.core.call("fmi3SetInt32", None, |c| {
                // SAFETY: both vectors hold `r.len()` elements.
                unsafe { (f.set_int32)(c, r.as_ptr(), r.len(), v.as_ptr(), r.len()) }
            })?);
        }
        if !enums.is_empty() {
            let r: Vec<u32> = enums.iter().map(|&i| refs[i]).collect();
            let v: Vec<i64> = enums.iter().map(|&i| i64::from(values[i])).collect();
            drop(self.core.call("fmi3SetInt64", None, |c| {
                // SAFETY: both vectors hold `r.len()` elements.
                unsafe { (f.set_int64)(c, r.as_ptr(), r.len(), v.as_ptr(), r.len()) }
            })?);
        }
        Ok(())
    }

    /// `fmi2GetInteger`, or in FMI 3.0 `fmi3GetInt32`, with enumerations read through
    /// `fmi3GetInt64`; an enumeration value outside `i32` is [`FmuError::OutOfRange`].
    pub fn get_integer(&self, refs: &[u32], values: &mut [i32]) -> Result<(), FmuError> {
        let f = match self.core.shared.api {
            Api::Fmi2(f) => {
                self.same_len("fmi2GetInteger", refs.len(), values.len())?;
                return self
                    .core
                    .call("fmi2GetInteger", None, |c| {
                        // SAFETY: both slices hold `refs.len()` elements.
                        unsafe {
                            (f.get_integer)(c, refs.as_ptr(), refs.len(), values.as_mut_ptr())
                        }
                    })
                    .map(drop);
            }
            Api::Fmi3(f) => f,
        };
        self.same_len("fmi3GetInt32", refs.len(), values.len())?;
        let (ints, enums) = self.split_enumerations(refs);
        if !ints.is_empty() {
            let r: Vec<u32> = ints.iter().map(|&i| refs[i]).collect();
            let mut v = vec![0i32; r.len()];
            drop(self.core.call("fmi3GetInt32", None, |c| {
                // SAFETY: both vectors hold `r.len()` elements.
                unsafe { (f.get_int32)(c, r.as_ptr(), r.len(), v.as_mut_ptr(), r.len()) }
            })?);
            for (&i, x) in ints.iter().zip(v) {
                values[i] = x;
            }
        }
        if !enums.is_empty() {
            let r: Vec<u32> = enums.iter().map(|&i| refs[i]).collect();
            let mut v = vec![0i64; r.len()];
            drop(self.core.call("fmi3GetInt64", None, |c| {
                // SAFETY: both vectors hold `r.len()` elements.
                unsafe { (f.get_int64)(c, r.as_ptr(), r.len(), v.as_mut_ptr(), r.len()) }
            })?);
            for ((&i, &vr), x) in enums.iter().zip(&r).zip(v) {
                values[i] = i32::try_from(x).map_err(|_| FmuError::OutOfRange {
                    fmu: self.core.shared.name.clone(),
                    function: "fmi3GetInt64",
                    value_reference: vr,
                    value: x,
                })?;
            }
        }
        Ok(())
    }

    /// `fmi2SetBoolean` (`fmi2Boolean` is an `int` 0/1 at the ABI) or `fmi3SetBoolean`
    /// (C `bool`, one byte).
    pub fn set_boolean(&mut self, refs: &[u32], values: &[bool]) -> Result<(), FmuError> {
        let n = refs.len();
        match self.core.shared.api {
            Api::Fmi2(f) => {
                self.same_len("fmi2SetBoolean", n, values.len())?;
                let ints: Vec<fmi2::Boolean> = values.iter().map(|&b| i32::from(b)).collect();
                self.core.call("fmi2SetBoolean", None, |c| {
                    // SAFETY: both slices hold `n` elements.
                    unsafe { (f.set_boolean)(c, refs.as_ptr(), n, ints.as_ptr()) }
                })
            }
            Api::Fmi3(f) => {
                self.same_len("fmi3SetBoolean", n, values.len())?;
                let bytes: Vec<fmi3::Boolean> = values.iter().map(|&b| u8::from(b)).collect();
                self.core.call("fmi3SetBoolean", None, |c| {
                    // SAFETY: both slices hold `n` elements.
                    unsafe { (f.set_boolean)(c, refs.as_ptr(), n, bytes.as_ptr(), n) }
                })
            }
        }
        .map(drop)
    }

    /// `fmi2GetBoolean` or `fmi3GetBoolean`; any non-zero value reads as true.
    pub fn get_boolean(&self, refs: &[u32], values: &mut [bool]) -> Result<(), FmuError> {
        let n = refs.len();
        match self.core.shared.api {
            Api::Fmi2(f) => {
                self.same_len("fmi2GetBoolean", n, values.len())?;
                let mut ints = vec![0 as fmi2::Boolean; n];
                drop(self.core.call("fmi2GetBoolean", None, |c| {
                    // SAFETY: both slices hold `n` elements.
                    unsafe { (f.get_boolean)(c, refs.as_ptr(), n, ints.as_mut_ptr()) }
                })?);
                for (v, i) in values.iter_mut().zip(ints) {
                    *v = i != 0;
                }
            }
            Api::Fmi3(f) => {
                self.same_len("fmi3GetBoolean", n, values.len())?;
                let mut bytes = vec![0 as fmi3::Boolean; n];
                drop(self.core.call("fmi3GetBoolean", None, |c| {
                    // SAFETY: both slices hold `n` elements.
                    unsafe { (f.get_boolean)(c, refs.as_ptr(), n, bytes.as_mut_ptr(), n) }
                })?);
                for (v, b) in values.iter_mut().zip(bytes) {
                    *v = b != 0;
                }
            }
        }
        Ok(())
    }

    /// Reads variables of one type, `kind`: the `refs` in order, `n_values` values in all
    /// (more than `refs.len()` where a reference is an FMI 3.0 array, whose elements
    /// follow each other in row-major order), appended to `out` in [`Value`]'s form of
    /// the type. FMI 2.0: `fmi2GetReal`, `fmi2GetInteger` (Integer, Enumeration),
    /// `fmi2GetBoolean`, `fmi2GetString`; FMI 3.0: `fmi3Get<Type>` (Enumeration through
    /// `fmi3GetInt64`). Strings and Binary values are copied at once (the FMU's pointers
    /// are valid only until its next call), each at most [`MAX_VALUE_BYTES`].
    pub fn get_values(
        &self,
        kind: VarKind,
        refs: &[u32],
        n_values: usize,
        out: &mut Vec<Value>,
    ) -> Result<(), FmuError> {
        if refs.is_empty() && n_values == 0 {
            return Ok(());
        }
        match self.core.shared.api {
            Api::Fmi2(f) => {
                if n_values != refs.len() {
                    // FMI 2.0 has no arrays: one value per reference.
                    return Err(self.length("fmi2Get*", refs.len(), n_values));
                }
                match kind {
                    VarKind::Real => {
                        let v = self.get2("fmi2GetReal", f.get_real, refs)?;
                        out.extend(v.into_iter().map(Value::Float));
                    }
                    VarKind::Integer | VarKind::Enumeration => {
                        let v = self.get2("fmi2GetInteger", f.get_integer, refs)?;
                        out.extend(v.into_iter().map(|i| Value::Int(i.into())));
                    }
                    VarKind::Boolean => {
                        let v = self.get2("fmi2GetBoolean", f.get_boolean, refs)?;
                        out.extend(v.into_iter().map(|b| Value::Bool(b != 0)));
                    }
                    VarKind::String => {
                        let (get, _) = f.string.ok_or_else(|| self.no_symbol("fmi2GetString"))?;
                        let v = self.get2("fmi2GetString", get, refs)?;
                        for (&p, &vr) in v.iter().zip(refs) {
                            out.push(Value::Text(self.text_value("fmi2GetString", vr, p)?));
                        }
                    }
                    other => return Err(self.not_fmi2(other, refs)),
                }
            }
            Api::Fmi3(f) => {
                let m = f.more;
                macro_rules! get {
                    ($name:literal, $fn:expr, $wrap:expr) => {{
                        let v = self.get3($name, $fn, refs, n_values)?;
                        out.extend(v.into_iter().map($wrap));
                    }};
                }
                match kind {
                    VarKind::Real => get!("fmi3GetFloat64", Some(f.get_float64), Value::Float),
                    VarKind::Float32 => {
                        get!("fmi3GetFloat32", m.float32.map(|p| p.0), Value::Float32)
                    }
                    VarKind::Integer => {
                        get!("fmi3GetInt32", Some(f.get_int32), |x| Value::Int(x.into()))
                    }
                    VarKind::Int64 | VarKind::Enumeration => {
                        get!("fmi3GetInt64", Some(f.get_int64), Value::Int)
                    }
                    VarKind::Int8 => {
                        get!("fmi3GetInt8", m.int8.map(|p| p.0), |x| Value::Int(x.into()))
                    }
                    VarKind::Int16 => {
                        get!("fmi3GetInt16", m.int16.map(|p| p.0), |x| Value::Int(
                            x.into()
                        ))
                    }
                    VarKind::UInt8 => {
                        get!("fmi3GetUInt8", m.uint8.map(|p| p.0), |x| Value::UInt(
                            x.into()
                        ))
                    }
                    VarKind::UInt16 => {
                        get!("fmi3GetUInt16", m.uint16.map(|p| p.0), |x| Value::UInt(
                            x.into()
                        ))
                    }
                    VarKind::UInt32 => {
                        get!("fmi3GetUInt32", m.uint32.map(|p| p.0), |x| Value::UInt(
                            x.into()
                        ))
                    }
                    VarKind::UInt64 => get!("fmi3GetUInt64", m.uint64.map(|p| p.0), Value::UInt),
                    VarKind::Boolean => {
                        get!("fmi3GetBoolean", Some(f.get_boolean), |b| Value::Bool(
                            b != 0
                        ))
                    }
                    VarKind::String => {
                        let v =
                            self.get3("fmi3GetString", m.string.map(|p| p.0), refs, n_values)?;
                        let vr = |i: usize| refs.get(i).or(refs.last()).copied().unwrap_or(0);
                        for (i, &p) in v.iter().enumerate() {
                            out.push(Value::Text(self.text_value("fmi3GetString", vr(i), p)?));
                        }
                    }
                    VarKind::Binary => {
                        let (get, _) = m.binary.ok_or_else(|| self.no_symbol("fmi3GetBinary"))?;
                        let mut sizes = vec![0usize; n_values];
                        let mut ptrs: Vec<fmi3::Binary> = vec![std::ptr::null(); n_values];
                        // The bytes are copied under the lock, before the FMU is called
                        // again.
                        let inner = self.core.call("fmi3GetBinary", None, |c| {
                            // SAFETY: `sizes` and `ptrs` hold `n_values` elements each.
                            unsafe {
                                get(
                                    c,
                                    refs.as_ptr(),
                                    refs.len(),
                                    sizes.as_mut_ptr(),
                                    ptrs.as_mut_ptr(),
                                    n_values,
                                )
                            }
                        })?;
                        let vr = |i: usize| refs.get(i).or(refs.last()).copied().unwrap_or(0);
                        for (i, (&size, &p)) in sizes.iter().zip(&ptrs).enumerate() {
                            if size > MAX_VALUE_BYTES {
                                return Err(self.too_long("fmi3GetBinary", vr(i), size));
                            }
                            if size == 0 {
                                out.push(Value::Bytes(Vec::new()));
                                continue;
                            }
                            if p.is_null() {
                                return Err(self.bad_value(
                                    "fmi3GetBinary",
                                    vr(i),
                                    format!("a null pointer for {size} bytes"),
                                ));
                            }
                            // SAFETY: the FMU gave `size` bytes at `p`, valid until its
                            // next call, which the held lock keeps from happening.
                            let bytes = unsafe { std::slice::from_raw_parts(p, size) };
                            out.push(Value::Bytes(bytes.to_vec()));
                        }
                        drop(inner);
                    }
                    VarKind::Clock => {
                        return Err(self.bad_value(
                            "fmi3GetClock",
                            refs[0],
                            "a Clock is not read: it needs event mode".into(),
                        ))
                    }
                }
            }
        }
        Ok(())
    }

    /// Sets scalar variables of one type, `kind`: `values[i]` (in [`Value`]'s form of
    /// the type) to `refs[i]`, with the functions [`Instance::get_values`] names. A
    /// value of another form or outside the type's range is [`FmuError::BadValue`].
    pub fn set_values(
        &mut self,
        kind: VarKind,
        refs: &[u32],
        values: &[Value],
    ) -> Result<(), FmuError> {
        let function = self.set_name(kind);
        self.same_len(function, refs.len(), values.len())?;
        if refs.is_empty() {
            return Ok(());
        }
        match self.core.shared.api {
            Api::Fmi2(f) => match kind {
                VarKind::Real => {
                    let v = self.convert(function, refs, values, float)?;
                    self.set_real(refs, &v)
                }
                VarKind::Integer | VarKind::Enumeration => {
                    let v = self.convert(function, refs, values, int::<i32>)?;
                    self.core
                        .call(function, None, |c| {
                            // SAFETY: both slices hold `refs.len()` elements.
                            unsafe { (f.set_integer)(c, refs.as_ptr(), refs.len(), v.as_ptr()) }
                        })
                        .map(drop)
                }
                VarKind::Boolean => {
                    let v = self.convert(function, refs, values, boolean)?;
                    self.set_boolean(refs, &v)
                }
                VarKind::String => {
                    let (_, set) = f.string.ok_or_else(|| self.no_symbol(function))?;
                    let texts = self.c_strings(function, refs, values)?;
                    let ptrs: Vec<*const c_char> = texts.iter().map(|t| t.as_ptr()).collect();
                    self.core
                        .call(function, None, |c| {
                            // SAFETY: both slices hold `refs.len()` elements; the strings
                            // live past the call.
                            unsafe { set(c, refs.as_ptr(), refs.len(), ptrs.as_ptr()) }
                        })
                        .map(drop)
                }
                other => Err(self.not_fmi2(other, refs)),
            },
            Api::Fmi3(f) => {
                let m = f.more;
                macro_rules! set {
                    ($fn:expr, $conv:expr) => {{
                        let v = self.convert(function, refs, values, $conv)?;
                        self.set3(function, $fn, refs, &v)
                    }};
                }
                match kind {
                    VarKind::Real => set!(Some(f.set_float64), float),
                    VarKind::Float32 => set!(m.float32.map(|p| p.1), |v: &Value| match *v {
                        Value::Float32(x) => Some(x),
                        _ => None,
                    }),
                    VarKind::Integer => set!(Some(f.set_int32), int::<i32>),
                    VarKind::Int64 | VarKind::Enumeration => set!(Some(f.set_int64), int::<i64>),
                    VarKind::Int8 => set!(m.int8.map(|p| p.1), int::<i8>),
                    VarKind::Int16 => set!(m.int16.map(|p| p.1), int::<i16>),
                    VarKind::UInt8 => set!(m.uint8.map(|p| p.1), uint::<u8>),
                    VarKind::UInt16 => set!(m.uint16.map(|p| p.1), uint::<u16>),
                    VarKind::UInt32 => set!(m.uint32.map(|p| p.1), uint::<u32>),
                    VarKind::UInt64 => set!(m.uint64.map(|p| p.1), uint::<u64>),
                    VarKind::Boolean => set!(Some(f.set_boolean), |v: &Value| {
                        boolean(v).map(u8::from)
                    }),
                    VarKind::String => {
                        let texts = self.c_strings(function, refs, values)?;
                        let ptrs: Vec<fmi3::Str> = texts.iter().map(|t| t.as_ptr()).collect();
                        self.set3(function, m.string.map(|p| p.1), refs, &ptrs)
                    }
                    VarKind::Binary => {
                        let (_, set) = m.binary.ok_or_else(|| self.no_symbol(function))?;
                        let bytes = self.convert(function, refs, values, |v: &Value| match v {
                            Value::Bytes(b) => Some(b.as_slice()),
                            _ => None,
                        })?;
                        let sizes: Vec<usize> = bytes.iter().map(|b| b.len()).collect();
                        let ptrs: Vec<fmi3::Binary> = bytes.iter().map(|b| b.as_ptr()).collect();
                        let n = refs.len();
                        self.core
                            .call(function, None, |c| {
                                // SAFETY: all slices hold `n` elements; the bytes live
                                // past the call.
                                unsafe {
                                    set(c, refs.as_ptr(), n, sizes.as_ptr(), ptrs.as_ptr(), n)
                                }
                            })
                            .map(drop)
                    }
                    VarKind::Clock => Err(self.bad_value(
                        function,
                        refs[0],
                        "a Clock is not set: it needs event mode".into(),
                    )),
                }
            }
        }
    }

    /// The setter [`Instance::set_values`] calls for `kind` in this FMU's version.
    fn set_name(&self, kind: VarKind) -> &'static str {
        if !self.core.fmi3() {
            return match kind {
                VarKind::Real => "fmi2SetReal",
                VarKind::Integer | VarKind::Enumeration => "fmi2SetInteger",
                VarKind::Boolean => "fmi2SetBoolean",
                _ => "fmi2SetString",
            };
        }
        match kind {
            VarKind::Real => "fmi3SetFloat64",
            VarKind::Float32 => "fmi3SetFloat32",
            VarKind::Integer => "fmi3SetInt32",
            VarKind::Int64 | VarKind::Enumeration => "fmi3SetInt64",
            VarKind::Int8 => "fmi3SetInt8",
            VarKind::Int16 => "fmi3SetInt16",
            VarKind::UInt8 => "fmi3SetUInt8",
            VarKind::UInt16 => "fmi3SetUInt16",
            VarKind::UInt32 => "fmi3SetUInt32",
            VarKind::UInt64 => "fmi3SetUInt64",
            VarKind::Boolean => "fmi3SetBoolean",
            VarKind::String => "fmi3SetString",
            VarKind::Binary => "fmi3SetBinary",
            VarKind::Clock => "fmi3SetClock",
        }
    }

    /// An FMI 2.0 getter's values (`n` = `refs.len()`).
    fn get2<T: Copy + Default>(
        &self,
        function: &'static str,
        f: fmi2::GetValues<T>,
        refs: &[u32],
    ) -> Result<Vec<T>, FmuError> {
        let mut v = vec![T::default(); refs.len()];
        drop(self.core.call(function, None, |c| {
            // SAFETY: both slices hold `refs.len()` elements.
            unsafe { f(c, refs.as_ptr(), refs.len(), v.as_mut_ptr()) }
        })?);
        Ok(v)
    }

    /// An FMI 3.0 getter's `n_values` values, or the missing function's error.
    fn get3<T: Copy + Default>(
        &self,
        function: &'static str,
        f: Option<fmi3::GetValues<T>>,
        refs: &[u32],
        n_values: usize,
    ) -> Result<Vec<T>, FmuError> {
        let f = f.ok_or_else(|| self.no_symbol(function))?;
        let mut v = vec![T::default(); n_values];
        drop(self.core.call(function, None, |c| {
            // SAFETY: `v` holds `n_values` elements, as passed.
            unsafe { f(c, refs.as_ptr(), refs.len(), v.as_mut_ptr(), n_values) }
        })?);
        Ok(v)
    }

    /// An FMI 3.0 setter on scalars, or the missing function's error.
    fn set3<T>(
        &self,
        function: &'static str,
        f: Option<fmi3::SetValues<T>>,
        refs: &[u32],
        values: &[T],
    ) -> Result<(), FmuError> {
        let f = f.ok_or_else(|| self.no_symbol(function))?;
        let n = refs.len();
        self.core
            .call(function, None, |c| {
                // SAFETY: both slices hold `n` elements (checked by the caller).
                unsafe { f(c, refs.as_ptr(), n, values.as_ptr(), n) }
            })
            .map(drop)
    }

    /// Each value in the setter's C form by `conv`, or [`FmuError::BadValue`] naming the
    /// first that has none.
    fn convert<'v, T>(
        &self,
        function: &'static str,
        refs: &[u32],
        values: &'v [Value],
        conv: impl Fn(&'v Value) -> Option<T>,
    ) -> Result<Vec<T>, FmuError> {
        values
            .iter()
            .zip(refs)
            .map(|(v, &vr)| {
                conv(v).ok_or_else(|| {
                    self.bad_value(function, vr, format!("{v:?} is not a value of its type"))
                })
            })
            .collect()
    }

    /// Strings as C strings for a setter.
    fn c_strings(
        &self,
        function: &'static str,
        refs: &[u32],
        values: &[Value],
    ) -> Result<Vec<CString>, FmuError> {
        let texts = self.convert(function, refs, values, |v: &Value| match v {
            Value::Text(s) => Some(s.as_str()),
            _ => None,
        })?;
        texts
            .into_iter()
            .map(|t| {
                CString::new(t).map_err(|_| FmuError::NulByte {
                    what: "String value",
                    value: t.replace('\0', "\\0"),
                })
            })
            .collect()
    }

    /// The text of a String an FMU gave: NUL-terminated within [`MAX_VALUE_BYTES`], not
    /// null.
    fn text_value(
        &self,
        function: &'static str,
        vr: u32,
        p: *const c_char,
    ) -> Result<String, FmuError> {
        if p.is_null() {
            return Err(self.bad_value(function, vr, "a null pointer for a String".into()));
        }
        let mut len = 0;
        // SAFETY: the FMU gave a NUL-terminated string; it is read up to its NUL, and no
        // further than MAX_VALUE_BYTES.
        while unsafe { *p.add(len) } != 0 {
            len += 1;
            if len > MAX_VALUE_BYTES {
                return Err(self.too_long(function, vr, len));
            }
        }
        // SAFETY: `len` bytes before the NUL, read above.
        let bytes = unsafe { std::slice::from_raw_parts(p.cast::<u8>(), len) };
        Ok(String::from_utf8_lossy(bytes).into_owned())
    }

    fn too_long(&self, function: &'static str, vr: u32, len: usize) -> FmuError {
        FmuError::CapExceeded {
            what: format!(
                "MAX_VALUE_BYTES (a value FMU '{}' gave through {function} for value \
                 reference {vr})",
                self.fmu_name()
            ),
            value: len as u64,
            limit: MAX_VALUE_BYTES as u64,
        }
    }

    fn bad_value(&self, function: &'static str, value_reference: u32, message: String) -> FmuError {
        FmuError::BadValue {
            fmu: self.core.shared.name.clone(),
            function,
            value_reference,
            message,
        }
    }

    fn no_symbol(&self, symbol: &'static str) -> FmuError {
        FmuError::MissingSymbol {
            fmu: self.core.shared.name.clone(),
            symbol,
        }
    }

    fn length(&self, function: &'static str, refs: usize, values: usize) -> FmuError {
        FmuError::LengthMismatch {
            fmu: self.core.shared.name.clone(),
            function,
            refs,
            values,
        }
    }

    /// An FMI 3.0 type asked of an FMI 2.0 FMU (its description cannot declare one).
    fn not_fmi2(&self, kind: VarKind, refs: &[u32]) -> FmuError {
        self.bad_value(
            "fmi2Get/Set",
            refs.first().copied().unwrap_or(0),
            format!("FMI 2.0 has no type {kind}"),
        )
    }

    /// `fmi2GetFMUstate` or `fmi3GetFMUState`: a copy of the instance's state. Refused
    /// without calling the FMU unless it declares `canGetAndSetFMUstate`
    /// (`canGetAndSetFMUState` in FMI 3.0).
    pub fn get_state(&self) -> Result<FmuState, FmuError> {
        let function = self.pick("fmi2GetFMUstate", "fmi3GetFMUState");
        let (get, _, _) = self.state_fns(function)?;
        let mut state: fmi2::State = std::ptr::null_mut();
        let guard = self.core.call(function, None, |c| {
            // SAFETY: a live component; a null `state` asks for a new one.
            unsafe { get(c, &mut state) }
        })?;
        drop(guard);
        self.wrap_state(function, state)
    }

    /// `fmi2SetFMUstate` or `fmi3SetFMUState`: back to `state`, which must come from this
    /// instance. Refused without calling the FMU unless it declares the capability.
    pub fn set_state(&mut self, state: &FmuState) -> Result<(), FmuError> {
        let function = self.pick("fmi2SetFMUstate", "fmi3SetFMUState");
        let (_, set, _) = self.state_fns(function)?;
        self.own(state, function)?;
        self.core
            .call(function, None, |c| {
                // SAFETY: a live state of this live component.
                unsafe { set(c, state.state) }
            })
            .map(drop)
    }

    /// `fmi2SerializedFMUstateSize` + `fmi2SerializeFMUstate` (or FMI 3.0's
    /// `fmi3SerializedFMUStateSize` + `fmi3SerializeFMUState`): `state` as bytes. Refused
    /// without calling the FMU unless it declares `canSerializeFMUstate`
    /// (`canSerializeFMUState`).
    pub fn serialize_state(&self, state: &FmuState) -> Result<Vec<u8>, FmuError> {
        let function = self.pick("fmi2SerializeFMUstate", "fmi3SerializeFMUState");
        let size_function = self.pick("fmi2SerializedFMUstateSize", "fmi3SerializedFMUStateSize");
        let serializer = self.serialize_fns(function)?;
        self.own(state, function)?;
        let size_of = match serializer {
            Serializer::Fmi2(size_of, _, _) | Serializer::Fmi3(size_of, _, _) => size_of,
        };
        let mut size = 0usize;
        drop(self.core.call(size_function, None, |c| {
            // SAFETY: a live state of this live component.
            unsafe { size_of(c, state.state, &mut size) }
        })?);
        if size > MAX_STATE_BYTES {
            return Err(FmuError::CapExceeded {
                what: format!(
                    "MAX_STATE_BYTES (serialized state of FMU '{}')",
                    self.fmu_name()
                ),
                value: size as u64,
                limit: MAX_STATE_BYTES as u64,
            });
        }
        let mut bytes = vec![0u8; size];
        drop(self.core.call(function, None, |c| match serializer {
            // SAFETY (both): `bytes` holds `size` bytes, as the FMU asked.
            Serializer::Fmi2(_, serialize, _) => unsafe {
                serialize(c, state.state, bytes.as_mut_ptr().cast::<c_char>(), size)
            },
            Serializer::Fmi3(_, serialize, _) => unsafe {
                serialize(c, state.state, bytes.as_mut_ptr(), size)
            },
        })?);
        Ok(bytes)
    }

    /// `fmi2DeSerializeFMUstate` or `fmi3DeserializeFMUState`: a state of this instance
    /// from bytes made by [`Instance::serialize_state`] (of this or another instance of
    /// the same FMU). Refused without calling the FMU unless it declares the capability.
    pub fn deserialize_state(&self, bytes: &[u8]) -> Result<FmuState, FmuError> {
        let function = self.pick("fmi2DeSerializeFMUstate", "fmi3DeserializeFMUState");
        let serializer = self.serialize_fns(function)?;
        let mut state: fmi2::State = std::ptr::null_mut();
        drop(self.core.call(function, None, |c| match serializer {
            // SAFETY (both): `bytes` is a live slice of the length given; a null `state`
            // asks for a new one.
            Serializer::Fmi2(_, _, deserialize) => unsafe {
                deserialize(c, bytes.as_ptr().cast::<c_char>(), bytes.len(), &mut state)
            },
            Serializer::Fmi3(_, _, deserialize) => unsafe {
                deserialize(c, bytes.as_ptr(), bytes.len(), &mut state)
            },
        })?);
        self.wrap_state(function, state)
    }

    /// The FMI 2.0 or the FMI 3.0 name, by the FMU's version.
    fn pick(&self, v2: &'static str, v3: &'static str) -> &'static str {
        if self.core.fmi3() {
            v3
        } else {
            v2
        }
    }

    /// FMI 3.0: the positions in `refs` of plain integers and of enumerations (by the
    /// description; a reference it does not name counts as an integer).
    fn split_enumerations(&self, refs: &[u32]) -> (Vec<usize>, Vec<usize>) {
        let variables = &self.core.shared.description.variables;
        (0..refs.len()).partition(|&i| {
            !variables
                .iter()
                .any(|v| v.value_reference == refs[i] && v.kind == VarKind::Enumeration)
        })
    }

    fn same_len(&self, function: &'static str, refs: usize, values: usize) -> Result<(), FmuError> {
        if refs == values {
            Ok(())
        } else {
            Err(FmuError::LengthMismatch {
                fmu: self.core.shared.name.clone(),
                function,
                refs,
                values,
            })
        }
    }

    fn missing(&self, capability: &'static str, function: &'static str) -> FmuError {
        FmuError::CapabilityMissing {
            fmu: self.core.shared.name.clone(),
            capability,
            function,
        }
    }

    /// The get/set/free state functions (the same C types in both versions), or the
    /// capability error.
    fn state_fns(
        &self,
        function: &'static str,
    ) -> Result<(fmi2::GetState, fmi2::SetState, fmi2::FreeState), FmuError> {
        let declared = self
            .core
            .shared
            .description
            .co_simulation
            .as_ref()
            .is_some_and(|c| c.can_get_and_set_fmu_state);
        let fns = match self.core.shared.api {
            Api::Fmi2(f) => f.state,
            Api::Fmi3(f) => f.state,
        };
        match fns {
            Some(fns) if declared => Ok(fns),
            _ => Err(self.missing(
                self.pick("canGetAndSetFMUstate", "canGetAndSetFMUState"),
                function,
            )),
        }
    }

    /// The serialization functions, or the capability error. Serialized states are
    /// useless without get/set, so both capabilities are required.
    fn serialize_fns(&self, function: &'static str) -> Result<Serializer, FmuError> {
        self.state_fns(function)?;
        let declared = self
            .core
            .shared
            .description
            .co_simulation
            .as_ref()
            .is_some_and(|c| c.can_serialize_fmu_state);
        let fns = match self.core.shared.api {
            Api::Fmi2(f) => f.serialize.map(|(a, b, c)| Serializer::Fmi2(a, b, c)),
            Api::Fmi3(f) => f.serialize.map(|(a, b, c)| Serializer::Fmi3(a, b, c)),
        };
        match fns {
            Some(fns) if declared => Ok(fns),
            _ => Err(self.missing(
                self.pick("canSerializeFMUstate", "canSerializeFMUState"),
                function,
            )),
        }
    }

    fn own(&self, state: &FmuState, function: &'static str) -> Result<(), FmuError> {
        if Arc::ptr_eq(&state.core, &self.core) {
            Ok(())
        } else {
            Err(FmuError::ForeignState {
                fmu: self.core.shared.name.clone(),
                function,
            })
        }
    }

    fn wrap_state(&self, function: &'static str, state: fmi2::State) -> Result<FmuState, FmuError> {
        if state.is_null() {
            return Err(FmuError::NullState {
                fmu: self.core.shared.name.clone(),
                function,
            });
        }
        Ok(FmuState {
            state,
            core: Arc::clone(&self.core),
        })
    }
}

/// A Real's value for a setter.
fn float(v: &Value) -> Option<f64> {
    match *v {
        Value::Float(x) => Some(x),
        _ => None,
    }
}

/// A signed integer's value as `T`, if in its range.
fn int<T: TryFrom<i64>>(v: &Value) -> Option<T> {
    match *v {
        Value::Int(i) => T::try_from(i).ok(),
        _ => None,
    }
}

/// An unsigned integer's value as `T`, if in its range.
fn uint<T: TryFrom<u64>>(v: &Value) -> Option<T> {
    match *v {
        Value::UInt(u) => T::try_from(u).ok(),
        _ => None,
    }
}

/// A Boolean's value.
fn boolean(v: &Value) -> Option<bool> {
    match *v {
        Value::Bool(b) => Some(b),
        _ => None,
    }
}

/// The size, serialize and deserialize functions of either version (their byte
/// pointers differ: `char` in FMI 2.0, `uint8_t` in FMI 3.0).
#[derive(Clone, Copy)]
enum Serializer {
    Fmi2(fmi2::StateSize, fmi2::Serialize, fmi2::Deserialize),
    Fmi3(fmi3::StateSize, fmi3::Serialize, fmi3::Deserialize),
}
