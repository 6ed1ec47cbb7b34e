//! Atomic file output: a run that fails leaves no half-written file behind.
//!
//! Two tools:
//!
//! * [`write_atomic`] / [`write_atomic_with`] replace one file. The bytes go to a temporary file
//!   in the target's directory (same file system, so the final `rename` is atomic), which is
//!   fsynced and then renamed over the target; the directory is fsynced afterwards. On any error
//!   (or a panic in the producer) the temporary file is removed and the target is untouched:
//!   a reader sees either the complete old file or the complete new one, never a mixture.
//!
//! * [`StagedDir`] collects a whole run's outputs in a hidden staging directory inside the
//!   output directory and moves them into place only on [`StagedDir::commit`]. Guarantee:
//!   if the run fails before `commit` (error, panic, early return), the output directory is
//!   exactly as it was (a directory that did not exist before and is still empty is removed
//!   again). During `commit` each file is replaced by an atomic `rename`, in the order the files
//!   were written; a crash in the middle of `commit` can leave some files new and some old, but
//!   never a truncated file. Write the file that marks a run as complete (e.g. `report.html`)
//!   last. Files in the output directory that the run did not write are left alone, so pointing
//!   `--out` at a directory holding other data is safe.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Counter that makes temporary names unique within this process (the pid makes them unique
/// across processes).
static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Prefix of every temporary file or staging directory this module creates.
pub const TMP_PREFIX: &str = ".ofmpc-tmp-";

/// Adds the path to an I/O error so the message says which file failed.
fn with_path(e: io::Error, what: &str, path: &Path) -> io::Error {
    io::Error::new(e.kind(), format!("{what} {}: {e}", path.display()))
}

/// A fresh name `<dir>/.ofmpc-tmp-<pid>-<n>-<stem>` next to `path`.
fn tmp_sibling(dir: &Path, stem: &str) -> PathBuf {
    let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    dir.join(format!("{TMP_PREFIX}{}-{n}-{stem}", std::process::id()))
}

/// The directory holding `path` (`.` for a bare file name).
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Makes a completed rename durable by fsyncing the directory. Best effort: some file systems
/// do not support fsync on directories, and the rename itself has already happened.
fn sync_dir(dir: &Path) {
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
}

/// Removes a temporary file when dropped unless [`TmpGuard::disarm`] was called; this covers
/// errors and panics alike.
struct TmpGuard {
    path: PathBuf,
    armed: bool,
}

impl TmpGuard {
    fn disarm(&mut self) {
        self.armed = false;
    }
}

impl Drop for TmpGuard {
    fn drop(&mut self) {
        if self.armed {
            let _ = fs::remove_file(&self.path);
        }
    }
}

/// Writes `bytes` to `path` atomically: temporary file in the same directory, fsync, rename over
/// the target. On failure the target is untouched and no temporary file remains.
///
/// The parent directory must exist. The new file gets default permissions (those of a newly
/// created file), not those of the file it replaces.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Like [`write_atomic`], but the content is produced by `fill`, which writes into the
/// temporary file. If `fill` returns an error (or panics), the temporary file is removed, the
/// target is untouched and the error is returned.
pub fn write_atomic_with<F>(path: &Path, fill: F) -> io::Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{} is not a file path (no file name)", path.display()),
        )
    })?;
    let dir = parent_dir(path);
    let stem = name.to_string_lossy();
    // create_new never reuses an existing file; on the (unlikely) collision take the next number.
    let (file, tmp) = loop {
        let tmp = tmp_sibling(dir, &stem);
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => break (f, tmp),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(with_path(e, "cannot create temporary file", &tmp)),
        }
    };
    let mut guard = TmpGuard {
        path: tmp,
        armed: true,
    };
    let mut w = io::BufWriter::new(file);
    fill(&mut w).map_err(|e| with_path(e, "cannot write", path))?;
    let file = w
        .into_inner()
        .map_err(|e| with_path(e.into_error(), "cannot write", path))?;
    file.sync_all()
        .map_err(|e| with_path(e, "cannot flush to disk", path))?;
    drop(file);
    fs::rename(&guard.path, path).map_err(|e| with_path(e, "cannot replace", path))?;
    guard.disarm();
    sync_dir(dir);
    Ok(())
}

/// Checks that `rel` is a plain relative path (no root, no `..`, not empty) so staged files
/// cannot escape the output directory.
fn check_relative(rel: &Path) -> io::Result<()> {
    let ok =
        rel.components().count() > 0 && rel.components().all(|c| matches!(c, Component::Normal(_)));
    if ok {
        Ok(())
    } else {
        Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "output file name {:?} must be a relative path inside the output directory \
                 (no leading '/', no '..')",
                rel
            ),
        ))
    }
}

/// An output directory whose files appear only when the whole run succeeded.
///
/// Files are written into a hidden staging directory `<target>/.ofmpc-tmp-<pid>-<n>-stage`
/// (same file system as the target, so moving them is a rename) and moved into `target` by
/// [`StagedDir::commit`]. Dropping a `StagedDir` without committing deletes the staging
/// directory, and `target` too if this value created it and it is still empty.
/// See the module documentation for the exact guarantee.
#[derive(Debug)]
pub struct StagedDir {
    target: PathBuf,
    staging: PathBuf,
    created_target: bool,
    /// Relative paths in the order they were written (commit order); no duplicates.
    files: Vec<PathBuf>,
    done: bool,
}

impl StagedDir {
    /// Prepares `target` (created with its parents if missing) and an empty staging directory.
    pub fn new(target: &Path) -> io::Result<Self> {
        let created_target = !target.exists();
        fs::create_dir_all(target)
            .map_err(|e| with_path(e, "cannot create output directory", target))?;
        let staging = loop {
            let s = tmp_sibling(target, "stage");
            match fs::create_dir(&s) {
                Ok(()) => break s,
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
                Err(e) => {
                    if created_target {
                        let _ = fs::remove_dir(target);
                    }
                    return Err(with_path(e, "cannot create staging directory", &s));
                }
            }
        };
        Ok(Self {
            target: target.to_path_buf(),
            staging,
            created_target,
            files: Vec::new(),
            done: false,
        })
    }

    /// The final output directory.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Where the staged (not yet committed) files live.
    pub fn staging(&self) -> &Path {
        &self.staging
    }

    /// Relative paths written so far, in commit order.
    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }

    /// Stages `bytes` as `rel` (a relative path, subdirectories allowed). Writing the same `rel`
    /// twice replaces the staged content; it keeps its first position in the commit order.
    pub fn write(&mut self, rel: impl AsRef<Path>, bytes: &[u8]) -> io::Result<()> {
        self.write_with(rel, |w| w.write_all(bytes))
    }

    /// Stages a file whose content `fill` writes. On error the file is not staged (a previous
    /// version staged under the same name stays).
    pub fn write_with<F>(&mut self, rel: impl AsRef<Path>, fill: F) -> io::Result<()>
    where
        F: FnOnce(&mut dyn Write) -> io::Result<()>,
    {
        let rel = rel.as_ref();
        check_relative(rel)?;
        let dest = self.staging.join(rel);
        let dir = parent_dir(&dest);
        fs::create_dir_all(dir).map_err(|e| with_path(e, "cannot create directory", dir))?;
        write_atomic_with(&dest, fill)?;
        if !self.files.iter().any(|f| f == rel) {
            self.files.push(rel.to_path_buf());
        }
        Ok(())
    }

    /// Moves every staged file into the target directory (one atomic rename per file, in
    /// write order), fsyncs the directories and removes the staging directory.
    pub fn commit(mut self) -> io::Result<()> {
        let mut dirs_to_sync: Vec<PathBuf> = vec![self.target.clone()];
        for rel in &self.files {
            let from = self.staging.join(rel);
            let to = self.target.join(rel);
            let dir = parent_dir(&to).to_path_buf();
            fs::create_dir_all(&dir).map_err(|e| with_path(e, "cannot create directory", &dir))?;
            if to.is_dir() {
                return Err(io::Error::new(
                    io::ErrorKind::AlreadyExists,
                    format!(
                        "cannot write {}: a directory of that name exists; move it away or \
                         choose another output directory",
                        to.display()
                    ),
                ));
            }
            fs::rename(&from, &to).map_err(|e| with_path(e, "cannot move into place", &to))?;
            if !dirs_to_sync.contains(&dir) {
                dirs_to_sync.push(dir);
            }
        }
        for d in &dirs_to_sync {
            sync_dir(d);
        }
        self.done = true;
        fs::remove_dir_all(&self.staging)
            .map_err(|e| with_path(e, "cannot remove staging directory", &self.staging))
    }
}

impl Drop for StagedDir {
    fn drop(&mut self) {
        if !self.done {
            let _ = fs::remove_dir_all(&self.staging);
            if self.created_target {
                // Succeeds only if nothing else was put there meanwhile.
                let _ = fs::remove_dir(&self.target);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Names in `dir` (not recursive), sorted.
    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn write_atomic_creates_and_replaces() {
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("a.txt");
        write_atomic(&p, b"first").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"first");
        write_atomic(&p, b"second, longer content").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"second, longer content");
        write_atomic(&p, b"").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"");
        assert_eq!(names(tmp.path()), vec!["a.txt"]);
    }

    #[test]
    fn failing_writer_leaves_old_file_and_no_temp() {
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("data.csv");
        write_atomic(&p, b"old complete content\n").unwrap();
        // Writes more than the BufWriter capacity so partial bytes really reach the temp file.
        let err = write_atomic_with(&p, |w| {
            w.write_all(&vec![b'x'; 100_000])?;
            Err(io::Error::other("simulated failure mid-way"))
        })
        .unwrap_err();
        assert!(
            err.to_string().contains("simulated failure mid-way"),
            "{err}"
        );
        assert!(err.to_string().contains("data.csv"), "{err}");
        assert_eq!(fs::read(&p).unwrap(), b"old complete content\n");
        assert_eq!(names(tmp.path()), vec!["data.csv"]);
    }

    #[test]
    fn panicking_writer_leaves_no_temp() {
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("x.bin");
        let r = std::panic::catch_unwind(|| {
            let _ = write_atomic_with(&p, |w| {
                w.write_all(b"partial")?;
                panic!("producer bug");
            });
        });
        assert!(r.is_err());
        assert!(names(tmp.path()).is_empty());
    }

    #[test]
    fn failure_without_target_creates_nothing() {
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("new.txt");
        let _ = write_atomic_with(&p, |_| Err(io::Error::other("no"))).unwrap_err();
        assert!(names(tmp.path()).is_empty());
    }

    #[test]
    fn missing_directory_is_a_clear_error() {
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("no/such/dir/f.txt");
        let e = write_atomic(&p, b"x").unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::NotFound);
        assert!(e.to_string().contains("no/such/dir"), "{e}");
    }

    #[test]
    fn rename_failure_keeps_target_and_removes_temp() {
        // The target is a non-empty directory: rename(file, dir) fails after the temp file was
        // fully written, exercising the late failure path.
        let tmp = tempfile::tempdir().unwrap();
        let p = tmp.path().join("out");
        fs::create_dir(&p).unwrap();
        fs::write(p.join("keep"), b"k").unwrap();
        assert!(write_atomic(&p, b"data").is_err());
        assert_eq!(names(tmp.path()), vec!["out"]);
        assert_eq!(fs::read(p.join("keep")).unwrap(), b"k");
    }

    #[test]
    fn staged_dir_commits_all_files() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("run");
        fs::create_dir(&out).unwrap();
        fs::write(out.join("unrelated.txt"), b"user data").unwrap();
        fs::write(out.join("a.csv"), b"old a").unwrap();
        let mut s = StagedDir::new(&out).unwrap();
        s.write("a.csv", b"new a").unwrap();
        s.write("fig/q.svg", b"<svg/>").unwrap();
        s.write("report.html", b"<html>").unwrap();
        // Nothing visible before commit.
        assert_eq!(fs::read(out.join("a.csv")).unwrap(), b"old a");
        assert!(!out.join("report.html").exists());
        assert_eq!(
            s.files(),
            &[
                PathBuf::from("a.csv"),
                PathBuf::from("fig/q.svg"),
                PathBuf::from("report.html")
            ]
        );
        s.commit().unwrap();
        assert_eq!(fs::read(out.join("a.csv")).unwrap(), b"new a");
        assert_eq!(fs::read(out.join("fig/q.svg")).unwrap(), b"<svg/>");
        assert_eq!(fs::read(out.join("report.html")).unwrap(), b"<html>");
        assert_eq!(fs::read(out.join("unrelated.txt")).unwrap(), b"user data");
        assert_eq!(
            names(&out),
            vec!["a.csv", "fig", "report.html", "unrelated.txt"]
        );
    }

    #[test]
    fn staged_dir_dropped_without_commit_changes_nothing() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("run");
        fs::create_dir(&out).unwrap();
        fs::write(out.join("a.csv"), b"old a").unwrap();
        {
            let mut s = StagedDir::new(&out).unwrap();
            s.write("a.csv", b"new a").unwrap();
            s.write("b.csv", b"new b").unwrap();
            let e = s
                .write_with("c.csv", |w| {
                    w.write_all(b"half")?;
                    Err(io::Error::other("simulation diverged"))
                })
                .unwrap_err();
            assert!(e.to_string().contains("simulation diverged"));
            // The run gives up here: s is dropped without commit.
        }
        assert_eq!(names(&out), vec!["a.csv"]);
        assert_eq!(fs::read(out.join("a.csv")).unwrap(), b"old a");
    }

    #[test]
    fn staged_dir_removes_a_target_it_created() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("fresh/run");
        {
            let mut s = StagedDir::new(&out).unwrap();
            s.write("a.csv", b"a").unwrap();
        }
        assert!(!out.exists());
    }

    #[test]
    fn staged_dir_rejects_escaping_paths() {
        let tmp = tempfile::tempdir().unwrap();
        let mut s = StagedDir::new(tmp.path()).unwrap();
        for bad in ["../x", "/etc/x", "", "a/../../b"] {
            let e = s.write(bad, b"x").unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput, "{bad}");
        }
        drop(s);
        assert!(names(tmp.path()).is_empty());
        assert!(!tmp.path().parent().unwrap().join("x").exists());
    }

    #[test]
    fn staged_dir_rewrite_keeps_first_position() {
        let tmp = tempfile::tempdir().unwrap();
        let mut s = StagedDir::new(tmp.path()).unwrap();
        s.write("a", b"1").unwrap();
        s.write("b", b"2").unwrap();
        s.write("a", b"3").unwrap();
        assert_eq!(s.files(), &[PathBuf::from("a"), PathBuf::from("b")]);
        s.commit().unwrap();
        assert_eq!(fs::read(tmp.path().join("a")).unwrap(), b"3");
        assert_eq!(names(tmp.path()), vec!["a", "b"]);
    }
}
