//! Where an output may be written. Every output file of every command goes through
//! [`check_output`] (via [`AtomicFile::create`]), which refuses:
//!
//! - a path that is, or is a hard link to, a file the command reads (its inputs);
//! - an existing file that is not a regular file (a device such as `/dev/full`, a FIFO,
//!   a socket, a directory);
//! - a symbolic link, whatever it points to: orbitlash never writes through a link
//!   (the target might be an input, or a file the user did not mean to replace); give
//!   the link's target instead;
//! - a path whose folder does not exist, unless the path is a default output under the
//!   project's `logs/`, whose folder is then created.
//!
//! Outputs are written to a temporary sibling and renamed into place when complete
//! (`atomic`), so the checks here are what stands between a typo and a lost input.

use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// What the command reads, and whether the output's folder may be created.
#[derive(Debug, Clone, Default)]
pub struct OutputPolicy {
    /// Files the command reads; no output may resolve to one of them.
    pub inputs: Vec<PathBuf>,
    /// Create missing parent folders (only for default paths under `logs/`).
    pub create_parents: bool,
}

impl OutputPolicy {
    /// A user-given output path for a command that reads `inputs`.
    pub fn reading(inputs: &[&Path]) -> OutputPolicy {
        OutputPolicy {
            inputs: inputs.iter().map(|p| p.to_path_buf()).collect(),
            create_parents: false,
        }
    }

    /// A default output under `logs/` (its folder is created when missing).
    pub fn default_in_logs(inputs: &[&Path]) -> OutputPolicy {
        OutputPolicy {
            create_parents: true,
            ..OutputPolicy::reading(inputs)
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot write {path}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("refusing to write {path}: {reason}")]
    Refused { path: String, reason: String },
    /// An output that an earlier error stopped: nothing is under its name.
    #[error("{path} was not written")]
    NotWritten { path: String },
}

impl OutputError {
    pub fn io(path: &Path, source: std::io::Error) -> OutputError {
        OutputError::Io {
            path: path.display().to_string(),
            source,
        }
    }

    pub fn refused(path: &Path, reason: impl Into<String>) -> OutputError {
        OutputError::Refused {
            path: path.display().to_string(),
            reason: reason.into(),
        }
    }

    /// Any other failure while writing `path`.
    pub fn other(path: &Path, message: impl std::fmt::Display) -> OutputError {
        OutputError::io(path, std::io::Error::other(message.to_string()))
    }

    /// A failure of the MCAP writer on `path`, keeping its I/O cause (a full disk says
    /// "No space left on device").
    pub fn mcap(path: &Path, e: mcap::McapError) -> OutputError {
        match e {
            mcap::McapError::Io(io) => OutputError::io(path, io),
            other => OutputError::other(path, other),
        }
    }
}

/// (device, inode) of the file `path` resolves to, following links.
fn identity(path: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
}

/// True when `a` and `b` are the same file (same inode, through any link or path).
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (identity(a), identity(b)) {
        (Some(x), Some(y)) => x == y,
        _ => false,
    }
}

/// The absolute path `path` stands for: its longest existing ancestor resolved through
/// links, then the rest of it with `.` and `..` applied. Two outputs of one command
/// must not resolve to the same path.
pub fn resolved(path: &Path) -> PathBuf {
    use std::path::Component;
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    // the file name itself is never followed (a link there is refused, not resolved)
    let (dir, file) = match (abs.parent(), abs.file_name()) {
        (Some(d), Some(f)) => (d.to_path_buf(), Some(f.to_owned())),
        _ => (abs.clone(), None),
    };
    let mut base = dir.clone();
    let mut rest: Vec<std::ffi::OsString> = Vec::new();
    let resolved_base = loop {
        if let Ok(p) = std::fs::canonicalize(&base) {
            break p;
        }
        match (base.file_name(), base.parent()) {
            (Some(f), Some(p)) => {
                rest.push(f.to_owned());
                base = p.to_path_buf();
            }
            _ => break base,
        }
    };
    let mut out = resolved_base;
    for part in rest
        .iter()
        .rev()
        .map(Path::new)
        .chain(file.as_deref().map(Path::new))
    {
        for c in part.components() {
            match c {
                Component::ParentDir => {
                    out.pop();
                }
                Component::CurDir => {}
                other => out.push(other.as_os_str()),
            }
        }
    }
    out
}

/// Every output one command will write, planned before any work starts: each is
/// checked against the inputs ([`check_output`]) and against every other output of the
/// command (the same path by any spelling, or an existing file under two names), so no
/// output replaces an input or another output. Files that go into an output folder
/// (`--plots DIR`, `--out DIR`) are planned by name too.
#[derive(Debug, Clone, Default)]
pub struct Outputs {
    policy: OutputPolicy,
    planned: Vec<Planned>,
    /// Folders the command creates when missing (`diagnose --out`): (path, resolved).
    created: Vec<(PathBuf, PathBuf)>,
}

#[derive(Debug, Clone)]
struct Planned {
    /// What the user called it: `--json`, `--plots (mesh-sensitivity.svg)`.
    label: String,
    path: PathBuf,
    resolved: PathBuf,
}

impl Outputs {
    /// The outputs of a command that reads `policy.inputs`.
    pub fn new(policy: OutputPolicy) -> Outputs {
        Outputs {
            policy,
            planned: Vec::new(),
            created: Vec::new(),
        }
    }

    /// Plans the output `path`, called `label` in messages (e.g. `--json`).
    pub fn file(&mut self, label: &str, path: &Path) -> Result<(), OutputError> {
        let in_created = path.parent().is_some_and(|d| {
            !d.exists() && {
                let rd = resolved(d);
                self.created.iter().any(|(_, c)| *c == rd)
            }
        });
        if in_created {
            // its folder does not exist yet: nothing there to replace, only the name
            let policy = OutputPolicy {
                create_parents: true,
                ..self.policy.clone()
            };
            check_output(path, &policy)?;
        } else {
            check_output(path, &self.policy)?;
        }
        let r = resolved(path);
        // a file where a planned folder is to be made, or inside a file's path
        for (d, rd) in &self.created {
            if *rd == r || rd.starts_with(&r) {
                return Err(OutputError::refused(
                    path,
                    format!(
                        "{label} would be a file where the folder {} is to be made",
                        d.display()
                    ),
                ));
            }
        }
        for p in &self.planned {
            if p.resolved == r || same_file(&p.path, path) {
                return Err(OutputError::refused(
                    path,
                    format!(
                        "{label} and {} would write the same file; give them different paths",
                        p.label
                    ),
                ));
            }
        }
        self.planned.push(Planned {
            label: label.to_string(),
            path: path.to_path_buf(),
            resolved: r,
        });
        Ok(())
    }

    /// Plans the folder `dir` (called `label`) that output files will be put in. It
    /// must be a folder; with `create`, a missing one is created by [`Outputs::create_folders`]
    /// (its parent must exist).
    pub fn folder(&mut self, label: &str, dir: &Path, create: bool) -> Result<(), OutputError> {
        let refuse = |why: String| OutputError::refused(dir, format!("{label}: {why}"));
        match std::fs::metadata(dir) {
            Ok(m) if m.is_dir() => Ok(()),
            Ok(m) => Err(refuse(format!("it is {}, not a directory", kind_of(&m)))),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                if std::fs::symlink_metadata(dir).is_ok() {
                    return Err(refuse("it is a broken symbolic link".into()));
                }
                if !create {
                    return Err(refuse("no such directory (create it first)".into()));
                }
                let parent = match dir.parent() {
                    Some(p) if !p.as_os_str().is_empty() => p,
                    _ => Path::new("."),
                };
                if parent.is_dir() {
                    let rd = resolved(dir);
                    if let Some(p) = self
                        .planned
                        .iter()
                        .find(|p| p.resolved == rd || rd.starts_with(&p.resolved))
                    {
                        return Err(refuse(format!(
                            "{} would write a file there ({})",
                            p.label,
                            p.path.display()
                        )));
                    }
                    self.created.push((dir.to_path_buf(), rd));
                    Ok(())
                } else {
                    Err(refuse(format!("no such directory: {}", parent.display())))
                }
            }
            Err(e) => Err(OutputError::io(dir, e)),
        }
    }

    /// Creates the planned folders that are missing.
    pub fn create_folders(&self) -> Result<(), OutputError> {
        for (d, _) in &self.created {
            if !d.is_dir() {
                std::fs::create_dir(d).map_err(|e| OutputError::io(d, e))?;
            }
        }
        Ok(())
    }

    /// Writes planned files whole, all or none: each goes to a temporary sibling, and
    /// only when every one was written are they renamed into place (a failure leaves
    /// no new file under any final name). Each path must have been planned.
    pub fn write_all(&self, files: &[(&Path, &[u8])]) -> Result<(), OutputError> {
        use std::io::Write as _;
        self.create_folders()?;
        let mut open = Vec::new();
        for (path, bytes) in files {
            assert!(
                self.planned.iter().any(|p| p.path == *path),
                "{} was not planned",
                path.display()
            );
            let policy = OutputPolicy {
                create_parents: false,
                ..self.policy.clone()
            };
            let mut f = AtomicFile::create(path, &policy)?;
            f.write_all(bytes).map_err(|e| OutputError::io(path, e))?;
            f.flush().map_err(|e| OutputError::io(path, e))?;
            open.push(f);
        }
        for f in open {
            f.commit()?;
        }
        Ok(())
    }
}

/// Checks that an input is a regular file (through links) before it is read: a FIFO or
/// a device would block or never end.
pub fn check_input(path: &Path) -> std::io::Result<()> {
    let meta = std::fs::metadata(path)?;
    if meta.is_file() {
        Ok(())
    } else {
        Err(std::io::Error::other(format!(
            "it is {}, not a regular file",
            kind_of(&meta)
        )))
    }
}

fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_dir() {
        "a directory"
    } else if t.is_file() {
        "a regular file"
    } else if t.is_symlink() {
        "a symbolic link"
    } else if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_socket() {
        "a socket"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else {
        "a file of an unknown kind"
    }
}

/// Suffix of the temporary file an output is written to before it is renamed into
/// place; output paths may not end with it.
pub const PARTIAL_SUFFIX: &str = ".partial";

/// Whether a file can be made in the folder `dir`: an empty file of a name no one
/// uses is created there and removed (permissions alone do not tell: a read-only
/// mount, or `/proc` and `/sys`, refuse files to root too). An output is written to a
/// sibling and renamed into place, so the folder's permission is the one that counts.
/// A name left by a probe that was killed is passed over, and a probe that cannot be
/// removed is no reason to refuse a folder that took it.
fn writable(dir: &Path) -> std::io::Result<()> {
    static PROBES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    loop {
        let n = PROBES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let probe = dir.join(format!(".orbitlash-probe-{}-{n}", std::process::id()));
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&probe)
        {
            Ok(_) => {
                let _ = std::fs::remove_file(&probe);
                return Ok(());
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && n < 1000 => continue,
            Err(e) => return Err(e),
        }
    }
}

/// Checks that `path` may be written under `policy` (see the module docs): the only
/// file made is the probe of its folder ([`writable`]), removed at once; a missing
/// default folder under `logs/` is created by [`prepare_output`].
pub fn check_output(path: &Path, policy: &OutputPolicy) -> Result<(), OutputError> {
    if path.as_os_str().is_empty() {
        return Err(OutputError::refused(path, "the path is empty"));
    }
    let text = path.as_os_str().to_string_lossy();
    if path.file_name().is_none() || text.ends_with('/') {
        return Err(OutputError::refused(
            path,
            "the path names a folder, not a file",
        ));
    }
    if text.ends_with(PARTIAL_SUFFIX) {
        return Err(OutputError::refused(
            path,
            format!("names ending in `{PARTIAL_SUFFIX}` are reserved for unfinished outputs"),
        ));
    }
    match std::fs::symlink_metadata(path) {
        Ok(meta) if meta.file_type().is_symlink() => {
            let target = std::fs::read_link(path)
                .map(|t| format!(" (to {})", t.display()))
                .unwrap_or_default();
            return Err(OutputError::refused(
                path,
                format!(
                    "it is a symbolic link{target}; orbitlash does not write through links, give the target's path instead"
                ),
            ));
        }
        Ok(meta) if !meta.file_type().is_file() => {
            return Err(OutputError::refused(
                path,
                format!("it is {}, not a regular file", kind_of(&meta)),
            ));
        }
        Ok(_) => {
            if let Some(input) = policy.inputs.iter().find(|i| same_file(path, i)) {
                return Err(OutputError::refused(
                    path,
                    if input == path {
                        "it is an input of this command; choose another output path".to_string()
                    } else {
                        format!(
                            "it is the same file as {}, an input of this command; choose another output path",
                            input.display()
                        )
                    },
                ));
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(OutputError::io(path, e)),
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    match std::fs::metadata(parent) {
        Ok(m) if m.is_dir() => writable(parent).map_err(|e| {
            OutputError::refused(
                path,
                format!("{} cannot be written in: {e}", parent.display()),
            )
        }),
        Ok(_) => Err(OutputError::refused(
            path,
            format!("{} is not a directory", parent.display()),
        )),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            if std::fs::symlink_metadata(parent).is_ok() {
                Err(OutputError::refused(
                    path,
                    format!("{} is a broken symbolic link", parent.display()),
                ))
            } else if policy.create_parents {
                Ok(())
            } else {
                Err(OutputError::refused(
                    path,
                    format!("no such directory: {}", parent.display()),
                ))
            }
        }
        Err(e) => Err(OutputError::io(path, e)),
    }
}

/// [`check_output`], then the default folder under `logs/` created when missing.
pub fn prepare_output(path: &Path, policy: &OutputPolicy) -> Result<(), OutputError> {
    check_output(path, policy)?;
    match path.parent() {
        Some(parent)
            if policy.create_parents && !parent.as_os_str().is_empty() && !parent.exists() =>
        {
            std::fs::create_dir_all(parent).map_err(|e| OutputError::io(path, e))
        }
        _ => Ok(()),
    }
}

/// Creates the temporary sibling an output is written to before it is renamed into
/// place: `<path>.<pid>.partial`, or with a counter after the process id when that
/// name is taken (by an input, another output of this process, a leftover). The file is
/// created new (`O_EXCL`: never through a link, never over anything), so concurrent
/// runs and a killed run's leftover `.partial` (kept for `orbitlash recover`) are
/// never touched.
pub fn create_temporary(
    path: &Path,
    policy: &OutputPolicy,
) -> Result<(PathBuf, std::fs::File), OutputError> {
    let pid = std::process::id();
    for k in 0..1000u32 {
        let mut s = path.as_os_str().to_owned();
        if k == 0 {
            s.push(format!(".{pid}{PARTIAL_SUFFIX}"));
        } else {
            s.push(format!(".{pid}-{k}{PARTIAL_SUFFIX}"));
        }
        let tmp = PathBuf::from(s);
        if policy.inputs.iter().any(|i| same_file(&tmp, i)) {
            continue;
        }
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
        {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(OutputError::io(path, e)),
        }
    }
    Err(OutputError::refused(
        path,
        "no free temporary name beside it",
    ))
}

/// Bytes free for an unprivileged writer on the file system that holds `path`'s
/// folder (statvfs), or `None` when it cannot be told.
pub fn available_bytes(path: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    let mut st = std::mem::MaybeUninit::<libc::statvfs>::uninit();
    // SAFETY: `c` is a valid NUL-terminated path and `st` is written by statvfs on success.
    let rc = unsafe { libc::statvfs(c.as_ptr(), st.as_mut_ptr()) };
    if rc != 0 {
        return None;
    }
    // SAFETY: statvfs returned 0, so it filled `st`.
    let st = unsafe { st.assume_init() };
    // The field types differ between platforms (u32 on some 32-bit ones).
    #[allow(clippy::unnecessary_cast)]
    Some((st.f_bavail as u64).saturating_mul(st.f_frsize as u64))
}

/// An output file written to a temporary sibling and renamed into place on success, so
/// a failed or interrupted run never leaves a half-written file under the final name.
pub struct AtomicFile {
    final_path: PathBuf,
    tmp_path: PathBuf,
    writer: Option<BufWriter<File>>,
    /// Logical write position, so that asking for it (as the MCAP writer often does)
    /// does not flush the buffer.
    position: u64,
}

impl AtomicFile {
    /// Creates `<path>.<pid>.partial` next to `path` after checking `path` against `policy`
    /// (`io::output`: never an input, a device, a FIFO or a link; parent folders only
    /// for defaults under `logs/`); fails now if the location cannot be written.
    pub fn create(path: &Path, policy: &OutputPolicy) -> Result<AtomicFile, OutputError> {
        prepare_output(path, policy)?;
        let (tmp_path, file) = create_temporary(path, policy)?;
        Ok(AtomicFile {
            final_path: path.to_path_buf(),
            tmp_path,
            writer: Some(BufWriter::with_capacity(1 << 16, file)),
            position: 0,
        })
    }

    /// The final path.
    pub fn path(&self) -> &Path {
        &self.final_path
    }

    pub fn writer(&mut self) -> &mut BufWriter<File> {
        self.writer.as_mut().expect("file not yet committed")
    }

    /// Flushes and renames the file into place, over any older file of that name. The
    /// rename is atomic: until it happens the older file stays whole under the final
    /// name (a run killed, out of disk or failed loses nothing that was there), and a
    /// crash never leaves a partial file under it. There is no fsync: it would double
    /// the cost of a logged run, and outputs are reproducible.
    pub fn commit(mut self) -> Result<PathBuf, OutputError> {
        let err = |source| OutputError::io(&self.final_path, source);
        let w = self.writer.take().expect("committed twice");
        let file = w.into_inner().map_err(|e| err(e.into_error()))?;
        drop(file);
        std::fs::rename(&self.tmp_path, &self.final_path).map_err(err)?;
        Ok(self.final_path.clone())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.writer().write(buf)?;
        self.position += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.writer().flush()
    }
}

impl Seek for AtomicFile {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        if pos == SeekFrom::Current(0) {
            return Ok(self.position);
        }
        self.position = self.writer().seek(pos)?;
        Ok(self.position)
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.writer.take().is_some() {
            let _ = std::fs::remove_file(&self.tmp_path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("orbitlash-output-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn core_refuses_inputs_links_and_devices() {
        let d = dir("refuse");
        let input = d.join("s.toml");
        std::fs::write(&input, "x").unwrap();
        let policy = OutputPolicy::reading(&[&input]);
        // the input itself, by another spelling, and through a hard link
        assert!(check_output(&input, &policy).is_err());
        assert!(check_output(&d.join(".").join("s.toml"), &policy).is_err());
        std::fs::hard_link(&input, d.join("hard.toml")).unwrap();
        assert!(check_output(&d.join("hard.toml"), &policy).is_err());
        // a link, even to a file that is not an input
        std::fs::write(d.join("other"), "y").unwrap();
        std::os::unix::fs::symlink(d.join("other"), d.join("link")).unwrap();
        let e = check_output(&d.join("link"), &policy)
            .unwrap_err()
            .to_string();
        assert!(e.contains("symbolic link"), "{e}");
        // devices and folders
        assert!(check_output(Path::new("/dev/null"), &policy).is_err());
        assert!(check_output(&d, &policy).is_err());
        // a new file in an existing folder is fine, one in a missing folder is not
        assert!(check_output(&d.join("new.mcap"), &policy).is_ok());
        let e = check_output(&d.join("missing/new.mcap"), &policy).unwrap_err();
        assert!(e.to_string().contains("no such directory"), "{e}");
        assert!(!d.join("missing").exists());
        // the default folder: checked without side effect, created when prepared
        let logs = OutputPolicy::default_in_logs(&[&input]);
        assert!(check_output(&d.join("logs/new.mcap"), &logs).is_ok());
        assert!(!d.join("logs").exists());
        assert!(prepare_output(&d.join("logs/new.mcap"), &logs).is_ok());
        assert!(d.join("logs").is_dir());
        // temporary names are reserved, and a folder path is not a file
        assert!(check_output(&d.join("x.mcap.partial"), &policy).is_err());
        assert!(check_output(Path::new("somewhere/"), &policy).is_err());
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn core_temporary_names_never_collide() {
        let d = dir("tmp");
        let out = d.join("run.mcap");
        let policy = OutputPolicy::reading(&[]);
        let (a, _fa) = create_temporary(&out, &policy).unwrap();
        let (b, _fb) = create_temporary(&out, &policy).unwrap();
        assert_ne!(a, b);
        assert!(a.to_string_lossy().ends_with(".partial"));
        // an input under the first free name is skipped, a link is not followed
        let pid = std::process::id();
        let input = d.join(format!("other.mcap.{pid}.partial"));
        std::fs::write(&input, "x").unwrap();
        let (c, _fc) =
            create_temporary(&d.join("other.mcap"), &OutputPolicy::reading(&[&input])).unwrap();
        assert_ne!(c, input);
        assert_eq!(std::fs::read(&input).unwrap(), b"x");
        let _ = std::fs::remove_dir_all(&d);
    }
}
