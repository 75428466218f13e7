//! Tasks run on the rayon pool's threads in a dependency order: a task starts once the
//! tasks it depends on have finished, and reads their outputs only. No barrier between
//! groups of tasks: a thread that finishes one takes the next whose dependencies are
//! done (docs/contact_barrier.md, "Several ribbons").
//!
//! Deterministic by construction: task i sees the outputs of `deps[i]`, which exist
//! before it starts, and nothing else that another task writes; which thread runs it and
//! when changes nothing. One thread runs the tasks in index order.

use std::sync::{Condvar, Mutex, OnceLock};

/// Which tasks have started and how many dependencies each still waits for.
struct Board<T> {
    items: Vec<Option<T>>,
    missing: Vec<usize>,
    started: usize,
    /// A task panicked: the others stop taking work (the panic reaches the caller
    /// through the scope).
    abandoned: bool,
}

/// Runs `task(i, items[i], outputs)` for every i, each after every task of `deps[i]`
/// (indices below i: the items come in a topological order) has finished;
/// `outputs[j]` holds task j's output from then on. Of the tasks ready to start, a free
/// thread takes the one of highest `priority` (then the lowest index): only the order
/// of the work, never its results. Returns the outputs in index order.
pub(super) fn run_in_dependency_order<T, O, F>(
    items: Vec<T>,
    (deps, priority): (&[Vec<usize>], &[f64]),
    task: F,
) -> Vec<O>
where
    T: Send,
    O: Send + Sync,
    F: Fn(usize, T, &[OnceLock<O>]) -> O + Sync,
{
    let n = items.len();
    debug_assert!(deps
        .iter()
        .enumerate()
        .all(|(i, d)| d.iter().all(|&j| j < i)));
    let outputs: Vec<OnceLock<O>> = (0..n).map(|_| OnceLock::new()).collect();
    let threads = rayon::current_num_threads().min(n);
    if threads <= 1 {
        for (i, item) in items.into_iter().enumerate() {
            let out = task(i, item, &outputs);
            let _ = outputs[i].set(out);
        }
    } else {
        let mut dependents = vec![Vec::new(); n];
        for (i, d) in deps.iter().enumerate() {
            for &j in d {
                dependents[j].push(i);
            }
        }
        let board = Mutex::new(Board {
            items: items.into_iter().map(Some).collect(),
            missing: deps.iter().map(Vec::len).collect(),
            started: 0,
            abandoned: false,
        });
        let ready = Condvar::new();
        let worker = || {
            while let Some((i, item)) = next_task(&board, &ready, priority) {
                let guard = AbandonOnPanic(&board, &ready);
                let out = task(i, item, &outputs);
                let _ = outputs[i].set(out);
                std::mem::forget(guard);
                let mut b = board.lock().unwrap_or_else(|e| e.into_inner());
                for &k in &dependents[i] {
                    b.missing[k] -= 1;
                }
                drop(b);
                ready.notify_all();
            }
        };
        rayon::scope(|s| {
            for _ in 0..threads {
                s.spawn(|_| worker());
            }
        });
    }
    outputs
        .into_iter()
        .map(|o| o.into_inner().expect("every task ran"))
        .collect()
}

/// The task of highest priority whose dependencies are done, waiting while none is
/// but some still run; None once every task has started (or one panicked).
fn next_task<T>(board: &Mutex<Board<T>>, ready: &Condvar, priority: &[f64]) -> Option<(usize, T)> {
    let mut b = board.lock().unwrap_or_else(|e| e.into_inner());
    loop {
        if b.abandoned || b.started == b.items.len() {
            return None;
        }
        let found = (0..b.items.len())
            .filter(|&i| b.missing[i] == 0 && b.items[i].is_some())
            .fold(None, |best: Option<usize>, i| match best {
                Some(j) if priority[j] >= priority[i] => Some(j),
                _ => Some(i),
            });
        if let Some(i) = found {
            b.started += 1;
            let item = b.items[i].take().expect("not started");
            return Some((i, item));
        }
        b = ready.wait(b).unwrap_or_else(|e| e.into_inner());
    }
}

/// Dropped only while a task unwinds: tells the waiting threads to stop.
struct AbandonOnPanic<'a, T>(&'a Mutex<Board<T>>, &'a Condvar);

impl<T> Drop for AbandonOnPanic<'_, T> {
    fn drop(&mut self) {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).abandoned = true;
        self.1.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A task sees exactly its dependencies' outputs, whatever the pool: the same
    /// results with 1 and 4 threads, and each task started after its dependencies.
    #[test]
    fn tasks_see_their_dependencies_outputs_on_any_pool() {
        let deps: Vec<Vec<usize>> = vec![vec![], vec![], vec![0], vec![1, 2], vec![], vec![3, 4]];
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a pool");
            pool.install(|| {
                let priority = [0.0, 1.0, 0.0, 0.0, 9.0, 0.0];
                run_in_dependency_order((0..6u64).collect(), (&deps, &priority), |i, item, outs| {
                    // every dependency's output exists; spin a little to mix the order
                    let mut x = item * 1000;
                    for &j in &deps[i] {
                        x += outs[j].get().expect("a dependency ran first");
                    }
                    (0..(6 - i) * 20_000).fold(x, |a, k| a ^ (k as u64 & 1))
                })
            })
        };
        let one = run(1);
        assert_eq!(one, vec![0, 1000, 2000, 6000, 4000, 15000]);
        assert_eq!(run(4), one);
    }

    /// A task that reads an output it does not depend on finds it missing on a pool
    /// where the tasks run side by side (the negative control: the rule above is what
    /// makes the outputs complete).
    #[test]
    fn an_undeclared_dependency_is_not_waited_for() {
        let deps: Vec<Vec<usize>> = vec![vec![], vec![]];
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("a pool");
        let (tx, rx) = std::sync::mpsc::channel::<()>();
        let rx = Mutex::new(rx);
        let seen = pool.install(|| {
            run_in_dependency_order(
                vec![0u8, 1],
                (&deps, &[0.0; 2]),
                |i, _, outs: &[OnceLock<bool>]| {
                    if i == 0 {
                        // task 0 waits until task 1 has looked (they run side by side)
                        rx.lock().unwrap().recv().expect("task 1 looked");
                        true
                    } else {
                        let seen = outs[0].get().is_some();
                        tx.send(()).expect("task 0 waits");
                        seen
                    }
                },
            )
        });
        assert!(
            !seen[1],
            "task 1 saw task 0's output without depending on it"
        );
    }

    /// A panicking task reaches the caller instead of leaving the others waiting.
    #[test]
    fn a_panicking_task_does_not_hang_the_others() {
        let deps: Vec<Vec<usize>> = vec![vec![], vec![0], vec![1]];
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("a pool");
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            pool.install(|| {
                run_in_dependency_order(
                    vec![0u8, 1, 2],
                    (&deps, &[0.0; 3]),
                    |i, _, _: &[OnceLock<u8>]| {
                        assert!(i != 0, "task 0 fails");
                        1
                    },
                )
            })
        }));
        assert!(result.is_err());
    }
}
