//! Files written straight into a run's staging directory and synced to disk on a thread of
//! their own ([`Syncer`]): the staging directory is read by no other process, so a file
//! there needs no temporary name, and the threads that write the files do not wait for the
//! disk. The run waits for the syncs ([`Syncer::finish`]) before it moves anything into
//! place, so the files are as durable as those written with a sync of their own.

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::thread::JoinHandle;

use anyhow::{Context, Result};

/// The thread that syncs the files [`Stager::write`] queues (errors ignored, as the sync of
/// an atomic write ignores them), until [`Syncer::finish`].
pub struct Syncer {
    queue: Option<mpsc::Sender<PathBuf>>,
    thread: Option<JoinHandle<()>>,
}

impl Syncer {
    /// Start the syncing thread.
    pub fn start() -> Self {
        let (queue, files) = mpsc::channel::<PathBuf>();
        let thread = std::thread::spawn(move || {
            for path in files {
                if let Ok(f) = fs::File::open(&path) {
                    f.sync_all().ok();
                }
            }
        });
        Self {
            queue: Some(queue),
            thread: Some(thread),
        }
    }

    /// A writer whose files this syncer syncs (once finished, the writer syncs each file
    /// itself).
    pub fn stager(&self) -> Stager<'_> {
        Stager {
            queue: self.queue.as_ref(),
        }
    }

    /// Wait until every queued file is synced; the thread ends.
    pub fn finish(&mut self) {
        drop(self.queue.take());
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

impl Drop for Syncer {
    fn drop(&mut self) {
        self.finish();
    }
}

/// Writes files into a staging directory and queues them on a [`Syncer`].
pub struct Stager<'a> {
    queue: Option<&'a mpsc::Sender<PathBuf>>,
}

impl Stager<'_> {
    /// Write `bytes` to `dir/name` (`dir` inside the staging directory) and queue the file
    /// for its sync; a failed write leaves no file.
    pub fn write(&self, dir: &Path, name: &str, bytes: &[u8]) -> Result<()> {
        let path = dir.join(name);
        if let Err(e) = fs::write(&path, bytes) {
            let _ = fs::remove_file(&path);
            return Err(e).with_context(|| format!("cannot write {}", path.display()));
        }
        match self.queue.map(|q| q.send(path.clone())) {
            Some(Ok(())) => {}
            // No syncing thread (finished, or its queue closed): sync here.
            _ => {
                if let Ok(f) = fs::File::open(&path) {
                    f.sync_all().ok();
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::Syncer;

    /// Files written through a stager are there with their bytes once the syncer finished,
    /// also those written after it finished; a write into a missing directory fails and
    /// leaves no file.
    #[test]
    fn staged_files_hold_their_bytes() {
        let dir = std::env::temp_dir().join(format!("rodloop-staging-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut syncer = Syncer::start();
        let names: Vec<String> = (0..20).map(|k| format!("f{k}.csv")).collect();
        {
            let stager = syncer.stager();
            std::thread::scope(|s| {
                for chunk in names.chunks(7) {
                    let stager = &stager;
                    let dir = &dir;
                    s.spawn(move || {
                        for n in chunk {
                            stager.write(dir, n, n.as_bytes()).unwrap();
                        }
                    });
                }
            });
            assert!(stager.write(&dir.join("missing"), "x.csv", b"x").is_err());
        }
        syncer.finish();
        syncer.stager().write(&dir, "late.csv", b"late").unwrap();
        for n in &names {
            assert_eq!(std::fs::read(dir.join(n)).unwrap(), n.as_bytes());
        }
        assert_eq!(std::fs::read(dir.join("late.csv")).unwrap(), b"late");
        assert!(!dir.join("missing").join("x.csv").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
