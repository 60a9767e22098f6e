//! The one thread pool of the crate: tracing the branches and the assembly's tasks
//! ([`run_parallel`]), and the plain map over a slice that the command-line tool uses for its
//! own per-state work ([`parallel_map`]).

use std::collections::VecDeque;
use std::sync::{mpsc, Mutex};

use crate::Progress;

/// Run `f` on every item on up to `threads` threads (taken in the order given: put the
/// longest first), forwarding the progress events `f` sends to `progress` and passing every
/// result to `done` as soon as it is ready, both on the calling thread; the results are
/// returned in the order of `items`.
pub(crate) fn run_parallel<T, R, F>(
    threads: usize,
    items: Vec<T>,
    progress: &mut dyn FnMut(Progress),
    done: &mut dyn FnMut(&R),
    f: F,
) -> Vec<R>
where
    T: Send,
    R: Send,
    F: Fn(T, &dyn Fn(Progress)) -> R + Sync,
{
    let count = items.len();
    if threads <= 1 || count <= 1 {
        let cell = std::cell::RefCell::new(progress);
        return items
            .into_iter()
            .map(|it| {
                let r = f(it, &|p| (cell.borrow_mut())(p));
                done(&r);
                r
            })
            .collect();
    }
    enum Msg<R> {
        Progress(Progress),
        Done(usize, R),
    }
    let queue = Mutex::new(items.into_iter().enumerate().collect::<VecDeque<_>>());
    let (tx, rx) = mpsc::channel::<Msg<R>>();
    let mut results: Vec<Option<R>> = (0..count).map(|_| None).collect();
    std::thread::scope(|scope| {
        for _ in 0..threads.min(count) {
            let tx = tx.clone();
            let queue = &queue;
            let f = &f;
            scope.spawn(move || loop {
                let next = queue.lock().map(|mut q| q.pop_front()).unwrap_or(None);
                let Some((i, item)) = next else { break };
                let txp = tx.clone();
                let r = f(item, &move |p| {
                    let _ = txp.send(Msg::Progress(p));
                });
                if tx.send(Msg::Done(i, r)).is_err() {
                    break;
                }
            });
        }
        drop(tx);
        for msg in rx {
            match msg {
                Msg::Progress(p) => progress(p),
                Msg::Done(i, r) => {
                    done(&r);
                    results[i] = Some(r);
                }
            }
        }
    });
    // Every item is popped by exactly one worker, which sends its result before taking the
    // next; a worker that panicked would have propagated out of the scope above.
    results.into_iter().flatten().collect()
}

/// `f` of every item of `items` on the available cores, in the order of `items` (the pool of
/// `run_parallel` without progress events).
pub fn parallel_map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    run_parallel(
        threads,
        items.iter().collect(),
        &mut |_| {},
        &mut |_| {},
        |item: &T, _| f(item),
    )
}

#[cfg(test)]
mod tests {
    use super::parallel_map;

    #[test]
    fn parallel_map_keeps_the_order_of_its_items() {
        let items: Vec<u64> = (0..257).collect();
        // Uneven work so that the workers finish out of order.
        let squares = parallel_map(&items, |&k| {
            (0..(k % 7) * 1000).fold(k * k, |a, _| std::hint::black_box(a))
        });
        assert_eq!(squares, items.iter().map(|k| k * k).collect::<Vec<_>>());
        assert!(parallel_map(&[] as &[u64], |&k| k).is_empty());
    }
}
