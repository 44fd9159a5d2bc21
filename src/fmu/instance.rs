//! A co-simulation instance of a loaded FMU and its saved states.
//!
//! Call sequence (FMI 2.0 co-simulation):
//!
//! ```text
//!   Fmu::instantiate ─▶ set_* (parameters, start values)
//!   setup_experiment(t0, stop) ─▶ enter_initialization_mode ─▶ set_*/get_* ─▶ exit_initialization_mode
//!   repeat: set_* (inputs) ─▶ do_step(t, h) ─▶ get_* (outputs)      t ← t + h
//!           get_state / set_state where canGetAndSetFMUstate, serialize where canSerializeFMUstate
//!   terminate ─▶ drop (fmi2FreeInstance)
//! ```
//!
//! Every call is made under the instance's mutex, checks the status returned, and after
//! an `fmi2Fatal` no further call (not even `fmi2FreeInstance`) reaches the FMU.

use std::ffi::{c_char, CString};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex, MutexGuard};

use super::fmi2::{self, CallbackFunctions, Component, Functions, LogTarget, Status};
use super::loaded::Loaded;
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
    /// keep the pointer) and of the logger's target; freed after `fmi2FreeInstance`.
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
            unsafe { (self.shared.fns.free_instance)(inner.component) };
        }
        // SAFETY: made by `Box::into_raw` in `Instance::new`, freed once here, after the
        // FMU has let go of them (or, after fmi2Fatal, is never called again).
        unsafe {
            drop(Box::from_raw(self.callbacks));
            drop(Box::from_raw(self.log));
        }
        self.shared.instances.fetch_sub(1, Ordering::SeqCst);
    }
}

/// One co-simulation instance of an [`super::Fmu`]. Freed (`fmi2FreeInstance`) when it and
/// every [`FmuState`] made from it are dropped.
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

/// A saved FMU state (`fmi2FMUstate`) of one instance; freed with `fmi2FreeFMUstate` on
/// drop. It keeps its instance alive, so dropping the [`Instance`] first is fine.
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
        // Every state is made under canGetAndSetFMUstate, so `free` is resolved.
        if let Some((_, _, free)) = self.core.shared.fns.state {
            // SAFETY: the state came from this component and is freed once.
            unsafe { free(inner.component, &mut self.state) };
        }
    }
}

impl Core {
    fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Makes one FMI call under the mutex and checks its status; `time` is the time the
    /// message names (`None`: the last communication point). On success the lock is
    /// handed back, so a caller can record what the call changed (the time) atomically.
    fn call(
        &self,
        function: &'static str,
        time: Option<f64>,
        f: impl FnOnce(Component, &Functions) -> Status,
    ) -> Result<MutexGuard<'_, Inner>, FmuError> {
        let mut inner = self.lock();
        if inner.fatal {
            return Err(FmuError::Unusable {
                fmu: self.shared.name.clone(),
                function,
            });
        }
        let status = f(inner.component, &self.shared.fns);
        let time = time.or(inner.time);
        match status {
            fmi2::OK => Ok(inner),
            fmi2::WARNING => {
                if self.logging {
                    use std::io::Write;
                    let _ = writeln!(
                        std::io::stderr(),
                        "[{}] {function} returned fmi2Warning",
                        self.name
                    );
                }
                Ok(inner)
            }
            other => {
                if other == fmi2::FATAL {
                    inner.fatal = true;
                }
                Err(FmuError::Status {
                    fmu: self.shared.name.clone(),
                    function,
                    time,
                    status: fmi2::status_name(other),
                })
            }
        }
    }
}

impl Instance {
    /// `fmi2Instantiate` for co-simulation, not visible, with the FMU's GUID and resource
    /// URI. The caller has counted the instance in `shared.instances`.
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
        }));
        let callbacks = Box::into_raw(Box::new(fmi2::callbacks(log)));
        // SAFETY: all pointers are valid NUL-terminated strings or live boxes; the
        // boxes live until after fmi2FreeInstance (Core::drop).
        let component = unsafe {
            (shared.fns.instantiate)(
                name.as_ptr(),
                fmi2::CO_SIMULATION,
                guid.as_ptr(),
                shared.resource_uri.as_ptr(),
                callbacks,
                0,
                i32::from(logging),
            )
        };
        if component.is_null() {
            // SAFETY: the FMU made no instance, so nothing refers to the boxes.
            unsafe {
                drop(Box::from_raw(callbacks));
                drop(Box::from_raw(log));
            }
            uncount(&shared);
            return Err(FmuError::NullInstance {
                fmu: shared.name.clone(),
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

    /// `fmi2SetupExperiment` from `start` [s] to `stop` [s] (if defined), tolerance
    /// undefined.
    pub fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Result<(), FmuError> {
        let (defined, stop_time) = (i32::from(stop.is_some()), stop.unwrap_or(0.0));
        let mut inner = self.core.call("fmi2SetupExperiment", Some(start), |c, f| {
            // SAFETY: a live component; plain values.
            unsafe { (f.setup_experiment)(c, 0, 0.0, start, defined, stop_time) }
        })?;
        inner.time = Some(start);
        Ok(())
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization_mode(&mut self) -> Result<(), FmuError> {
        self.core
            .call("fmi2EnterInitializationMode", None, |c, f| {
                // SAFETY: a live component.
                unsafe { (f.enter_initialization_mode)(c) }
            })
            .map(drop)
    }

    /// `fmi2ExitInitializationMode`.
    pub fn exit_initialization_mode(&mut self) -> Result<(), FmuError> {
        self.core
            .call("fmi2ExitInitializationMode", None, |c, f| {
                // SAFETY: a live component.
                unsafe { (f.exit_initialization_mode)(c) }
            })
            .map(drop)
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Result<(), FmuError> {
        self.core
            .call("fmi2Terminate", None, |c, f| {
                // SAFETY: a live component.
                unsafe { (f.terminate)(c) }
            })
            .map(drop)
    }

    /// `fmi2Reset`: back to the state right after instantiation.
    pub fn reset(&mut self) -> Result<(), FmuError> {
        let mut inner = self.core.call("fmi2Reset", None, |c, f| {
            // SAFETY: a live component.
            unsafe { (f.reset)(c) }
        })?;
        inner.time = None;
        Ok(())
    }

    /// `fmi2DoStep` from the communication point `t` [s] over `h` [s]; inputs are held
    /// over the step as set. Prior states may still be restored afterwards
    /// (`noSetFMUStatePriorToCurrentPoint` = false).
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<(), FmuError> {
        let mut inner = self.core.call("fmi2DoStep", Some(t), |c, f| {
            // SAFETY: a live component; plain values.
            unsafe { (f.do_step)(c, t, h, 0) }
        })?;
        inner.time = Some(t + h);
        Ok(())
    }

    /// `fmi2SetReal`: `values[i]` to the variable `refs[i]`.
    pub fn set_real(&mut self, refs: &[u32], values: &[f64]) -> Result<(), FmuError> {
        self.same_len("fmi2SetReal", refs.len(), values.len())?;
        self.core
            .call("fmi2SetReal", None, |c, f| {
                // SAFETY: both slices hold `refs.len()` elements.
                unsafe { (f.set_real)(c, refs.as_ptr(), refs.len(), values.as_ptr()) }
            })
            .map(drop)
    }

    /// `fmi2GetReal`: the variable `refs[i]` into `values[i]`.
    pub fn get_real(&self, refs: &[u32], values: &mut [f64]) -> Result<(), FmuError> {
        self.same_len("fmi2GetReal", refs.len(), values.len())?;
        self.core
            .call("fmi2GetReal", None, |c, f| {
                // SAFETY: both slices hold `refs.len()` elements.
                unsafe { (f.get_real)(c, refs.as_ptr(), refs.len(), values.as_mut_ptr()) }
            })
            .map(drop)
    }

    /// `fmi2SetInteger`.
    pub fn set_integer(&mut self, refs: &[u32], values: &[i32]) -> Result<(), FmuError> {
        self.same_len("fmi2SetInteger", refs.len(), values.len())?;
        self.core
            .call("fmi2SetInteger", None, |c, f| {
                // SAFETY: both slices hold `refs.len()` elements.
                unsafe { (f.set_integer)(c, refs.as_ptr(), refs.len(), values.as_ptr()) }
            })
            .map(drop)
    }

    /// `fmi2GetInteger`.
    pub fn get_integer(&self, refs: &[u32], values: &mut [i32]) -> Result<(), FmuError> {
        self.same_len("fmi2GetInteger", refs.len(), values.len())?;
        self.core
            .call("fmi2GetInteger", None, |c, f| {
                // SAFETY: both slices hold `refs.len()` elements.
                unsafe { (f.get_integer)(c, refs.as_ptr(), refs.len(), values.as_mut_ptr()) }
            })
            .map(drop)
    }

    /// `fmi2SetBoolean` (`fmi2Boolean` is an `int` 0/1 at the ABI).
    pub fn set_boolean(&mut self, refs: &[u32], values: &[bool]) -> Result<(), FmuError> {
        self.same_len("fmi2SetBoolean", refs.len(), values.len())?;
        let ints: Vec<fmi2::Boolean> = values.iter().map(|&b| i32::from(b)).collect();
        self.core
            .call("fmi2SetBoolean", None, |c, f| {
                // SAFETY: both slices hold `refs.len()` elements.
                unsafe { (f.set_boolean)(c, refs.as_ptr(), refs.len(), ints.as_ptr()) }
            })
            .map(drop)
    }

    /// `fmi2GetBoolean`; any non-zero `int` reads as true.
    pub fn get_boolean(&self, refs: &[u32], values: &mut [bool]) -> Result<(), FmuError> {
        self.same_len("fmi2GetBoolean", refs.len(), values.len())?;
        let mut ints = vec![0 as fmi2::Boolean; refs.len()];
        drop(self.core.call("fmi2GetBoolean", None, |c, f| {
            // SAFETY: both slices hold `refs.len()` elements.
            unsafe { (f.get_boolean)(c, refs.as_ptr(), refs.len(), ints.as_mut_ptr()) }
        })?);
        for (v, i) in values.iter_mut().zip(ints) {
            *v = i != 0;
        }
        Ok(())
    }

    /// `fmi2GetFMUstate`: a copy of the instance's state. Refused without calling the
    /// FMU unless it declares `canGetAndSetFMUstate`.
    pub fn get_state(&self) -> Result<FmuState, FmuError> {
        let (get, _, _) = self.state_fns("fmi2GetFMUstate")?;
        let mut state: fmi2::State = std::ptr::null_mut();
        let guard = self.core.call("fmi2GetFMUstate", None, |c, _| {
            // SAFETY: a live component; a null `state` asks for a new one.
            unsafe { get(c, &mut state) }
        })?;
        drop(guard);
        self.wrap_state("fmi2GetFMUstate", state)
    }

    /// `fmi2SetFMUstate`: back to `state`, which must come from this instance. Refused
    /// without calling the FMU unless it declares `canGetAndSetFMUstate`.
    pub fn set_state(&mut self, state: &FmuState) -> Result<(), FmuError> {
        let (_, set, _) = self.state_fns("fmi2SetFMUstate")?;
        self.own(state, "fmi2SetFMUstate")?;
        self.core
            .call("fmi2SetFMUstate", None, |c, _| {
                // SAFETY: a live state of this live component.
                unsafe { set(c, state.state) }
            })
            .map(drop)
    }

    /// `fmi2SerializedFMUstateSize` + `fmi2SerializeFMUstate`: `state` as bytes. Refused
    /// without calling the FMU unless it declares `canSerializeFMUstate`.
    pub fn serialize_state(&self, state: &FmuState) -> Result<Vec<u8>, FmuError> {
        let (size_of, serialize, _) = self.serialize_fns("fmi2SerializeFMUstate")?;
        self.own(state, "fmi2SerializeFMUstate")?;
        let mut size = 0usize;
        drop(self.core.call("fmi2SerializedFMUstateSize", None, |c, _| {
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
        drop(self.core.call("fmi2SerializeFMUstate", None, |c, _| {
            // SAFETY: `bytes` holds `size` bytes, as the FMU asked.
            unsafe { serialize(c, state.state, bytes.as_mut_ptr().cast::<c_char>(), size) }
        })?);
        Ok(bytes)
    }

    /// `fmi2DeSerializeFMUstate`: a state of this instance from bytes made by
    /// [`Instance::serialize_state`] (of this or another instance of the same FMU).
    /// Refused without calling the FMU unless it declares `canSerializeFMUstate`.
    pub fn deserialize_state(&self, bytes: &[u8]) -> Result<FmuState, FmuError> {
        let (_, _, deserialize) = self.serialize_fns("fmi2DeSerializeFMUstate")?;
        let mut state: fmi2::State = std::ptr::null_mut();
        drop(self.core.call("fmi2DeSerializeFMUstate", None, |c, _| {
            // SAFETY: `bytes` is a live slice of the length given; a null `state` asks
            // for a new one.
            unsafe { deserialize(c, bytes.as_ptr().cast::<c_char>(), bytes.len(), &mut state) }
        })?);
        self.wrap_state("fmi2DeSerializeFMUstate", state)
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

    /// The get/set/free state functions, or the capability error.
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
        match self.core.shared.fns.state {
            Some(fns) if declared => Ok(fns),
            _ => Err(self.missing("canGetAndSetFMUstate", function)),
        }
    }

    /// The serialization functions, or the capability error. Serialized states are
    /// useless without get/set, so both capabilities are required.
    fn serialize_fns(
        &self,
        function: &'static str,
    ) -> Result<(fmi2::StateSize, fmi2::Serialize, fmi2::Deserialize), FmuError> {
        self.state_fns(function)?;
        let declared = self
            .core
            .shared
            .description
            .co_simulation
            .as_ref()
            .is_some_and(|c| c.can_serialize_fmu_state);
        match self.core.shared.fns.serialize {
            Some(fns) if declared => Ok(fns),
            _ => Err(self.missing("canSerializeFMUstate", function)),
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
