//! The one thread pool of the crate: tracing the branches and the assembly's tasks.

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
