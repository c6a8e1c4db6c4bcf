//! Protocol Buffers wire format: a small encoder for the log's messages and a decoder
//! that reads them back through the descriptors stored in the log.
//! <https://protobuf.dev/programming-guides/encoding/>

/// Appends fields to a message buffer.
#[derive(Debug, Default, Clone)]
pub struct Encoder {
    pub buf: Vec<u8>,
    /// Buffers reused for nested messages, whose length must precede them.
    pool: Vec<Vec<u8>>,
}

const VARINT: u32 = 0;
const FIXED64: u32 = 1;
const LEN: u32 = 2;
const FIXED32: u32 = 5;

impl Encoder {
    pub fn clear(&mut self) {
        self.buf.clear();
    }

    fn varint(&mut self, mut v: u64) {
        while v >= 0x80 {
            self.buf.push((v as u8) | 0x80);
            v >>= 7;
        }
        self.buf.push(v as u8);
    }

    fn key(&mut self, field: u32, wire: u32) {
        self.varint(u64::from((field << 3) | wire));
    }

    pub fn double(&mut self, field: u32, v: f64) {
        self.key(field, FIXED64);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    pub fn uint64(&mut self, field: u32, v: u64) {
        self.key(field, VARINT);
        self.varint(v);
    }

    /// int64 and int32 (and enums): two's complement as a 64-bit varint.
    pub fn int64(&mut self, field: u32, v: i64) {
        self.key(field, VARINT);
        self.varint(v as u64);
    }

    pub fn fixed32(&mut self, field: u32, v: u32) {
        self.key(field, FIXED32);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    pub fn string(&mut self, field: u32, s: &str) {
        self.key(field, LEN);
        self.varint(s.len() as u64);
        self.buf.extend_from_slice(s.as_bytes());
    }

    /// A packed `repeated double`.
    pub fn packed_doubles(&mut self, field: u32, values: impl ExactSizeIterator<Item = f64>) {
        self.key(field, LEN);
        self.varint(8 * values.len() as u64);
        for v in values {
            self.buf.extend_from_slice(&v.to_le_bytes());
        }
    }

    /// A nested message written by `f` (which may nest further).
    pub fn message(&mut self, field: u32, f: impl FnOnce(&mut Encoder)) {
        let mut buf = self.pool.pop().unwrap_or_default();
        buf.clear();
        let mut inner = Encoder {
            buf,
            pool: std::mem::take(&mut self.pool),
        };
        f(&mut inner);
        self.pool = inner.pool;
        self.key(field, LEN);
        self.varint(inner.buf.len() as u64);
        self.buf.extend_from_slice(&inner.buf);
        self.pool.push(inner.buf);
    }
}

/// One decoded field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Wire<'a> {
    Varint(u64),
    Fixed64([u8; 8]),
    Fixed32([u8; 4]),
    Len(&'a [u8]),
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("malformed protobuf message at byte {0}")]
pub struct Malformed(pub usize);

/// Splits a message into (field number, value) pairs.
pub fn fields(mut data: &[u8]) -> Result<Vec<(u32, Wire<'_>)>, Malformed> {
    let total = data.len();
    let mut out = Vec::new();
    let varint = |d: &mut &[u8]| -> Result<u64, Malformed> {
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let (&b, rest) = d.split_first().ok_or(Malformed(total - d.len()))?;
            *d = rest;
            v |= u64::from(b & 0x7f) << shift;
            if b < 0x80 {
                return Ok(v);
            }
        }
        Err(Malformed(total - d.len()))
    };
    while !data.is_empty() {
        let at = total - data.len();
        let key = varint(&mut data)?;
        let field = (key >> 3) as u32;
        if field == 0 {
            // no protobuf field has number 0 (zeros where a message should be)
            return Err(Malformed(at));
        }
        fn take<'a>(d: &mut &'a [u8], n: usize, at: usize) -> Result<&'a [u8], Malformed> {
            if d.len() < n {
                return Err(Malformed(at));
            }
            let (a, b) = d.split_at(n);
            *d = b;
            Ok(a)
        }
        let value = match (key & 7) as u32 {
            VARINT => Wire::Varint(varint(&mut data)?),
            FIXED64 => Wire::Fixed64(take(&mut data, 8, at)?.try_into().expect("8 bytes")),
            FIXED32 => Wire::Fixed32(take(&mut data, 4, at)?.try_into().expect("4 bytes")),
            LEN => {
                let n = varint(&mut data)? as usize;
                Wire::Len(take(&mut data, n, at)?)
            }
            _ => return Err(Malformed(at)),
        };
        out.push((field, value));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let mut e = Encoder::default();
        e.double(1, 293.15);
        e.uint64(2, 300);
        e.int64(3, -2);
        e.string(4, "eclipse entry");
        e.packed_doubles(5, [1.0, -2.5].into_iter());
        e.message(6, |m| {
            m.double(1, 7.0);
            m.message(2, |n| n.uint64(1, 5));
        });
        e.fixed32(7, 9);
        let f = fields(&e.buf).unwrap();
        assert_eq!(f[0], (1, Wire::Fixed64(293.15f64.to_le_bytes())));
        assert_eq!(f[1], (2, Wire::Varint(300)));
        assert_eq!(f[2], (3, Wire::Varint(-2i64 as u64)));
        assert_eq!(f[3], (4, Wire::Len(b"eclipse entry")));
        assert!(matches!(f[4], (5, Wire::Len(b)) if b.len() == 16));
        let Wire::Len(inner) = f[5].1 else { panic!() };
        let inner = fields(inner).unwrap();
        assert_eq!(inner[0], (1, Wire::Fixed64(7.0f64.to_le_bytes())));
        let Wire::Len(deeper) = inner[1].1 else {
            panic!()
        };
        assert_eq!(fields(deeper).unwrap(), vec![(1, Wire::Varint(5))]);
        assert_eq!(f[6], (7, Wire::Fixed32(9u32.to_le_bytes())));
        assert!(fields(&[0x0a, 0x05, 1]).is_err());
    }
}
