//! Output files written to a temporary sibling and renamed into place on success, so
//! a failed or interrupted run never leaves a half-written file under the final name.

use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

pub use super::output::{OutputError, OutputPolicy};
use super::output::{create_temporary, prepare_output};

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
