//! Every length field of an MCAP record checked against the bytes that are there,
//! before a parser allocates what the field says. The mcap crate's parser reserves a
//! string's or a map's declared size before reading it, so one damaged length (a flipped
//! byte, `0xffffff7f` written over a string's length) asks for 4 GB and aborts the
//! process; checked here first, the same damage is a "record … is malformed" error.
//!
//! The layouts are the MCAP specification's (records 0x01–0x0f); other opcodes are
//! skipped whole, as readers must.

/// Reads a record body field by field, each length checked against what is left.
struct Fields<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Fields<'a> {
    fn left(&self) -> usize {
        self.b.len() - self.at
    }

    fn skip(&mut self, n: u64, what: &str) -> Result<(), String> {
        match usize::try_from(n) {
            Ok(n) if n <= self.left() => {
                self.at += n;
                Ok(())
            }
            _ => Err(format!(
                "its {what} claims {n} bytes where {} are left",
                self.left()
            )),
        }
    }

    fn u32(&mut self, what: &str) -> Result<u64, String> {
        let s = self
            .b
            .get(self.at..self.at + 4)
            .ok_or(format!("{what} cut off"))?;
        self.at += 4;
        Ok(u32::from_le_bytes(s.try_into().expect("4 bytes")) as u64)
    }

    fn u64(&mut self, what: &str) -> Result<u64, String> {
        let s = self
            .b
            .get(self.at..self.at + 8)
            .ok_or(format!("{what} cut off"))?;
        self.at += 8;
        Ok(u64::from_le_bytes(s.try_into().expect("8 bytes")))
    }

    /// A u32-length-prefixed string or byte array.
    fn prefixed(&mut self, what: &str) -> Result<(), String> {
        let n = self.u32(what)?;
        self.skip(n, what)
    }

    /// A u64-length-prefixed byte array.
    fn prefixed64(&mut self, what: &str) -> Result<(), String> {
        let n = self.u64(what)?;
        self.skip(n, what)
    }

    /// A map or array: a u32 byte length, then entries of which each must fit in it.
    fn map(
        &mut self,
        what: &str,
        entry: fn(&mut Fields<'a>) -> Result<(), String>,
    ) -> Result<(), String> {
        let n = self.u32(what)?;
        let start = self.at;
        self.skip(n, what)?;
        let mut inner = Fields {
            b: &self.b[start..self.at],
            at: 0,
        };
        while inner.left() > 0 {
            entry(&mut inner)?;
        }
        Ok(())
    }
}

fn string_pair(f: &mut Fields<'_>) -> Result<(), String> {
    f.prefixed("map key")?;
    f.prefixed("map value")
}

fn fixed(n: u64) -> impl Fn(&mut Fields<'_>) -> Result<(), String> {
    move |f| f.skip(n, "entry")
}

/// Checks the length fields of a record of opcode `op` whose body is `body`.
pub fn check_record(op: u8, body: &[u8]) -> Result<(), String> {
    let f = &mut Fields { b: body, at: 0 };
    match op {
        0x01 => {
            f.prefixed("profile")?;
            f.prefixed("library")?;
        }
        0x02 => f.skip(20, "footer")?,
        0x03 => {
            f.skip(2, "schema id")?;
            f.prefixed("schema name")?;
            f.prefixed("schema encoding")?;
            f.prefixed("schema data")?;
        }
        0x04 => {
            f.skip(4, "channel ids")?;
            f.prefixed("topic")?;
            f.prefixed("message encoding")?;
            f.map("channel metadata", string_pair)?;
        }
        0x05 => f.skip(22, "message header")?,
        0x06 => {
            f.skip(16, "chunk times")?;
            let uncompressed = f.u64("uncompressed size")?;
            f.skip(4, "chunk CRC")?;
            let compression_at = f.at;
            f.prefixed("compression")?;
            let compressed = f.u64("records length")?;
            f.skip(compressed, "records")?;
            let plain = f.at - compression_at == 4 + 8 + compressed as usize;
            // an uncompressed chunk holds exactly its size; a compressed one is
            // decompressed into a buffer of the stated size: bounded, so a damaged
            // size cannot ask for more than any compression gives
            if (plain && uncompressed != compressed)
                || uncompressed
                    > compressed
                        .saturating_mul(MAX_COMPRESSION_RATIO)
                        .max(1 << 20)
            {
                return Err(format!(
                    "its uncompressed size {uncompressed} does not fit its {compressed} bytes"
                ));
            }
        }
        0x07 => {
            f.skip(2, "channel id")?;
            f.map("message index", |e| fixed(16)(e))?;
        }
        0x08 => {
            f.skip(32, "chunk index offsets")?;
            f.map("message index offsets", |e| fixed(10)(e))?;
            f.skip(8, "message index length")?;
            f.prefixed("compression")?;
            f.skip(16, "chunk sizes")?;
        }
        0x09 => {
            f.skip(16, "attachment times")?;
            f.prefixed("attachment name")?;
            f.prefixed("media type")?;
            f.prefixed64("attachment data")?;
            f.skip(4, "attachment CRC")?;
        }
        0x0a => {
            f.skip(40, "attachment index")?;
            f.prefixed("attachment name")?;
            f.prefixed("media type")?;
        }
        0x0b => {
            f.skip(42, "statistics")?;
            f.map("channel message counts", |e| fixed(10)(e))?;
        }
        0x0c => {
            f.prefixed("metadata name")?;
            f.map("metadata", string_pair)?;
        }
        0x0d => {
            f.skip(16, "metadata index")?;
            f.prefixed("metadata name")?;
        }
        0x0e => f.skip(17, "summary offset")?,
        0x0f => f.skip(4, "data end")?,
        _ => {}
    }
    Ok(())
}

/// The largest ratio of a chunk's uncompressed to compressed size accepted (zstd and
/// lz4 reach a few hundred on repetitive data; past this a size field is damaged).
pub const MAX_COMPRESSION_RATIO: u64 = 4096;

/// Calls `f(offset, opcode, body start, body end)` for each record of `b` from `at`
/// (while `f` says go on), up to the last whole one; a record whose length runs past
/// `b` is an error at its offset ("runs past `past`").
fn walk(
    b: &[u8],
    mut at: usize,
    past: &str,
    mut f: impl FnMut(usize, u8, usize, usize) -> Result<bool, (usize, String)>,
) -> Result<(), (usize, String)> {
    while at + 9 <= b.len() {
        let len = u64::from_le_bytes(b[at + 1..at + 9].try_into().expect("8 bytes"));
        let start = at + 9;
        let end = usize::try_from(len)
            .ok()
            .and_then(|l| start.checked_add(l))
            .filter(|&e| e <= b.len())
            .ok_or_else(|| (at, format!("its length {len} runs past {past}")))?;
        if !f(at, b[at], start, end)? {
            break;
        }
        at = end;
    }
    Ok(())
}

/// Checks every record of an MCAP file (`bytes` after the magic) and the records inside
/// each uncompressed chunk; a record that runs past the end (a file cut off, or a
/// damaged length) is an error too. `Err((offset, message))` names the first bad one.
pub fn check_file(bytes: &[u8], magic_len: usize) -> Result<(), (usize, String)> {
    walk(
        bytes,
        magic_len,
        "the end of the file",
        |at, op, start, end| {
            let body = &bytes[start..end];
            check_record(op, body).map_err(|m| (at, m))?;
            if op == 0x06 {
                check_chunk_records(body).map_err(|(o, m)| (start + o, m))?;
            }
            // the footer ends the records; the closing magic follows
            Ok(op != 0x02)
        },
    )
}

/// The records inside an uncompressed chunk body (a compressed one is checked by its
/// sizes alone).
fn check_chunk_records(body: &[u8]) -> Result<(), (usize, String)> {
    let name_len = u32::from_le_bytes(body[28..32].try_into().expect("checked")) as usize;
    if name_len != 0 {
        return Ok(());
    }
    walk(body, 32 + 8, "its chunk", |at, op, start, end| {
        check_record(op, &body[start..end]).map_err(|m| (at, m))?;
        Ok(true)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn core_a_length_past_the_body_is_refused_before_parsing() {
        // a metadata record: name "n", one pair "k" -> "v"
        let mut body = Vec::new();
        body.extend(1u32.to_le_bytes());
        body.push(b'n');
        let pair = [&1u32.to_le_bytes()[..], b"k", &1u32.to_le_bytes(), b"v"].concat();
        body.extend((pair.len() as u32).to_le_bytes());
        body.extend(&pair);
        assert!(check_record(0x0c, &body).is_ok());
        assert!(mcap::parse_record(0x0c, &body).is_ok());
        // every length field made huge in turn is refused
        for at in [0usize, 5, 9, 14] {
            let mut bad = body.clone();
            bad[at..at + 4].copy_from_slice(&0x7fff_ffffu32.to_le_bytes());
            assert!(check_record(0x0c, &bad).is_err(), "offset {at}");
        }
    }
}
