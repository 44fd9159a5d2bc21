//! Property test of the kernel's event order: any sequence of schedule / pop / cancel
//! operations pops events in non-decreasing `(time, class)` order, FIFO within equal
//! `(time, class)`, exactly as a plain reference model (a `Vec` in insertion order from
//! which the first minimum by `(time, class)` is taken, i.e. a stable sort) would.

use dsmcosim::kernel::{EventClass, EventKey, Kernel, KernelError, SimTime};
use proptest::prelude::*;

#[derive(Debug, Clone)]
enum Op {
    /// Schedule at `now + delay`.
    In { delay: u64, class: usize },
    /// Schedule at an absolute time, possibly in the past.
    At { time: u64, class: usize },
    /// Pop the earliest event.
    Pop,
    /// Cancel the events whose id is `rem` modulo `modulus`.
    Cancel { modulus: u64, rem: u64 },
    /// Replace the kernel by a clone of itself (forks must behave identically).
    Fork,
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        4 => (0u64..6, 0usize..7).prop_map(|(delay, class)| Op::In { delay, class }),
        2 => (0u64..40, 0usize..7).prop_map(|(time, class)| Op::At { time, class }),
        4 => Just(Op::Pop),
        1 => (2u64..6, 0u64..6).prop_map(|(modulus, rem)| Op::Cancel { modulus, rem }),
        1 => Just(Op::Fork),
    ]
}

/// The reference: pending `(time, class, id)` in insertion order.
struct Model {
    pending: Vec<(SimTime, EventClass, u64)>,
    now: SimTime,
    /// Class of the last pop (`Measurement`, the first, before any pop).
    now_class: EventClass,
}

impl Default for Model {
    fn default() -> Self {
        Model {
            pending: Vec::new(),
            now: SimTime::ZERO,
            now_class: EventClass::Measurement,
        }
    }
}

impl Model {
    fn pop(&mut self) -> Option<(SimTime, EventClass, u64)> {
        // `min_by_key` returns the first of equal minima: insertion order breaks ties.
        let (i, _) = self
            .pending
            .iter()
            .enumerate()
            .min_by_key(|(_, &(t, c, _))| (t, c))?;
        let e = self.pending.remove(i);
        self.now = e.0;
        self.now_class = e.1;
        Some(e)
    }
}

fn run(ops: &[Op]) -> Result<(), TestCaseError> {
    let mut kernel: Kernel<u64> = Kernel::new();
    let mut model = Model::default();
    let mut next_id = 0u64;
    let mut last_pop: Option<EventKey> = None;
    let mut last_id_at: Option<((SimTime, EventClass), u64)> = None;

    for (step, op) in ops.iter().enumerate() {
        match *op {
            Op::In { delay, class } | Op::At { time: delay, class } => {
                let class = EventClass::ALL[class];
                let (result, time) = match *op {
                    Op::In { .. } => (
                        kernel.schedule_in(SimTime(delay), class, next_id),
                        SimTime(model.now.0 + delay),
                    ),
                    _ => (
                        kernel.schedule(SimTime(delay), class, next_id),
                        SimTime(delay),
                    ),
                };
                if time < model.now {
                    prop_assert_eq!(
                        result,
                        Err(KernelError::Past {
                            time,
                            now: model.now
                        }),
                        "op {}: scheduling in the past must fail",
                        step
                    );
                } else if time == model.now && class < model.now_class {
                    prop_assert_eq!(
                        result,
                        Err(KernelError::EarlierClass {
                            time,
                            class,
                            current: model.now_class
                        }),
                        "op {}: scheduling before the current class must fail",
                        step
                    );
                } else {
                    let key = result.map_err(|e| {
                        TestCaseError::fail(format!("op {step}: unexpected error {e}"))
                    })?;
                    prop_assert_eq!(key.time, time, "op {}", step);
                    prop_assert_eq!(key.class, class, "op {}", step);
                    model.pending.push((time, class, next_id));
                    next_id += 1;
                }
            }
            Op::Pop => {
                let got = kernel.pop();
                let want = model.pop();
                prop_assert_eq!(
                    got.map(|(k, e)| (k.time, k.class, e)),
                    want,
                    "op {}: pop differs from the reference",
                    step
                );
                if let Some((key, id)) = got {
                    if let Some(prev) = last_pop {
                        prop_assert!(
                            (prev.time, prev.class) <= (key.time, key.class),
                            "op {}: {:?} popped after {:?}",
                            step,
                            key,
                            prev
                        );
                        prop_assert!(prev < key, "op {}: keys must increase", step);
                    }
                    if let Some((tc, prev_id)) = last_id_at {
                        if tc == (key.time, key.class) {
                            prop_assert!(prev_id < id, "op {}: not FIFO", step);
                        }
                    }
                    last_pop = Some(key);
                    last_id_at = Some(((key.time, key.class), id));
                }
            }
            Op::Cancel { modulus, rem } => {
                let removed = kernel.cancel_if(|&id| id % modulus == rem);
                let before = model.pending.len();
                model.pending.retain(|&(_, _, id)| id % modulus != rem);
                prop_assert_eq!(removed, before - model.pending.len(), "op {}", step);
            }
            Op::Fork => {
                let fork = kernel.clone();
                prop_assert_eq!(
                    fork.pending().collect::<Vec<_>>(),
                    kernel.pending().collect::<Vec<_>>(),
                    "op {}",
                    step
                );
                kernel = fork;
            }
        }
        prop_assert_eq!(kernel.now(), model.now, "op {}: now", step);
        prop_assert_eq!(kernel.len(), model.pending.len(), "op {}: len", step);
        // `pending()` lists exactly what the reference would pop, in that order.
        let mut sorted = model.pending.clone();
        sorted.sort_by_key(|&(t, c, _)| (t, c)); // stable: FIFO within equal keys
        let listed: Vec<_> = kernel
            .pending()
            .map(|(k, &e)| (k.time, k.class, e))
            .collect();
        prop_assert_eq!(listed, sorted.clone(), "op {}: pending()", step);
        prop_assert_eq!(
            kernel.peek().map(|k| (k.time, k.class)),
            sorted.first().map(|&(t, c, _)| (t, c)),
            "op {}: peek",
            step
        );
    }
    // Drain what is left: still in order.
    while let Some((key, id)) = kernel.pop() {
        let want = model.pop();
        prop_assert_eq!(Some((key.time, key.class, id)), want, "drain");
    }
    prop_assert!(model.pending.is_empty());
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn pops_in_key_order_and_match_the_reference(ops in prop::collection::vec(op(), 0..300)) {
        run(&ops)?;
    }
}
