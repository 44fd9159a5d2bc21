//! Criterion benchmark of the event kernel under the classic *hold* model: keep `N`
//! events pending; repeatedly pop the earliest and schedule one new event at
//! `now + delay` (seeded pseudo-random delay and class). Measured for the
//! [`Kernel<u64>`] and, in the same group so their ratio comes from one run, for a bare
//! `priority_queue::PriorityQueue<u64, Reverse<(u64, u8, u64)>>` doing the same
//! pushes and pops with the same keys, twice: with the crate's default hasher (SipHash)
//! and with the kernel's [`SlotHasher`], so that the kernel's own overhead (payload
//! slab, free list, checked keys) shows apart from the choice of hasher.
//!
//! Run: `cargo bench --bench kernel` (add a filter, e.g. `-- hold/kernel`, for one).
//! Throughput is in events (one pop + one push) per second.

use std::cmp::Reverse;
use std::hash::BuildHasherDefault;
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use dsmcosim::kernel::{EventClass, Kernel, SimTime, SlotHasher};
use priority_queue::PriorityQueue;
use rand_chacha::rand_core::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Hold operations per timed iteration.
const OPS: usize = 1024;
/// Length of the pre-drawn table of (delay, class); a power of two.
const TABLE: usize = 1 << 16;

/// Seeded delays [ns] (multiples of 1 µs in 1 µs ..= 1 ms, so equal times occur among
/// pending events and the class and seq parts of the key are exercised; never zero,
/// since a zero delay with an earlier class than the popped event is rejected by the
/// kernel) and classes.
fn draws(seed: u64) -> Vec<(u64, EventClass)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..TABLE)
        .map(|_| {
            let r = rng.next_u64();
            (
                (1 + r % 1000) * 1000,
                EventClass::ALL[((r >> 32) % 7) as usize],
            )
        })
        .collect()
}

fn filled_kernel(n: usize, draws: &[(u64, EventClass)]) -> Kernel<u64> {
    let mut k = Kernel::with_capacity(n);
    for (i, &(delay, class)) in draws.iter().cycle().take(n).enumerate() {
        k.schedule(SimTime(delay), class, i as u64)
            .expect("initial events are in the future");
    }
    k
}

type Bare<H> = PriorityQueue<u64, Reverse<(u64, u8, u64)>, H>;

fn filled_bare<H: std::hash::BuildHasher + Default>(
    n: usize,
    draws: &[(u64, EventClass)],
) -> (Bare<H>, u64) {
    let mut q = Bare::with_capacity_and_default_hasher(n);
    let mut seq = 0u64;
    for &(delay, class) in draws.iter().cycle().take(n) {
        q.push(seq, Reverse((delay, class as u8, seq)));
        seq += 1;
    }
    (q, seq)
}

/// The hold loop on a bare queue: pop the earliest, push one at `now + delay`.
fn bench_bare<H: std::hash::BuildHasher + Default>(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    n: usize,
    draws: &[(u64, EventClass)],
) {
    let (mut bare, mut seq) = filled_bare::<H>(n, draws);
    let mut next = n;
    group.bench_function(BenchmarkId::new(name, n), |b| {
        b.iter(|| {
            for _ in 0..OPS {
                let (_, Reverse((now, _, _))) = bare.pop().expect("hold keeps n events");
                let (delay, class) = draws[next % TABLE];
                next += 1;
                let time = now.checked_add(delay).expect("future event");
                bare.push(black_box(seq), Reverse((time, class as u8, seq)));
                seq += 1;
            }
        })
    });
    assert_eq!(bare.len(), n);
}

fn bench_hold(c: &mut Criterion) {
    let draws = draws(0x5eed);
    let mut group = c.benchmark_group("hold");
    group.throughput(Throughput::Elements(OPS as u64));
    for n in [64usize, 100_000] {
        // A timed iteration at 100 000 pending events takes ~1 ms: fewer samples keep
        // the run near criterion's default 5 s per benchmark.
        group.sample_size(if n >= 100_000 { 50 } else { 100 });
        let mut kernel = filled_kernel(n, &draws);
        let mut next = n;
        group.bench_function(BenchmarkId::new("kernel", n), |b| {
            b.iter(|| {
                for _ in 0..OPS {
                    let (_, event) = kernel.pop().expect("hold keeps n events");
                    let (delay, class) = draws[next % TABLE];
                    next += 1;
                    kernel
                        .schedule_in(SimTime(delay), class, black_box(event) + 1)
                        .expect("future event");
                }
            })
        });
        assert_eq!(kernel.len(), n);

        bench_bare::<std::hash::RandomState>(&mut group, "bare_priority_queue", n, &draws);
        bench_bare::<BuildHasherDefault<SlotHasher>>(
            &mut group,
            "bare_priority_queue_slot_hasher",
            n,
            &draws,
        );
    }
    group.finish();
}

criterion_group!(benches, bench_hold);
criterion_main!(benches);
