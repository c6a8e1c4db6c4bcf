//! Protocol Buffers wire format: a small encoder for the log's messages, whose schemas
//! are built at run time (`io::log_schema`). Reading them back goes through the stored
//! descriptors with `prost-reflect` (`io::mcap_read`).
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

#[cfg(test)]
mod tests {
    use super::*;
    use prost_reflect::{DescriptorPool, DynamicMessage, Value};
    use prost_types::field_descriptor_proto::{Label, Type};
    use prost_types::{
        DescriptorProto, FieldDescriptorProto, FileDescriptorProto, FileDescriptorSet,
    };

    fn message(name: &str, fields: &[(&str, i32, Type, Option<&str>)]) -> DescriptorProto {
        DescriptorProto {
            name: Some(name.into()),
            field: fields
                .iter()
                .map(|&(n, number, ty, type_name)| FieldDescriptorProto {
                    name: Some(n.into()),
                    number: Some(number),
                    r#type: Some(ty as i32),
                    label: Some(if n == "e" {
                        Label::Repeated
                    } else {
                        Label::Optional
                    } as i32),
                    type_name: type_name.map(Into::into),
                    ..Default::default()
                })
                .collect(),
            ..Default::default()
        }
    }

    /// What the encoder writes, read back by an independent decoder (`prost-reflect`)
    /// through a descriptor written here by hand.
    #[test]
    fn val_prost_reflect_decodes_what_the_encoder_writes() {
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
        let file = FileDescriptorProto {
            name: Some("t.proto".into()),
            package: Some("t".into()),
            syntax: Some("proto3".into()),
            message_type: vec![
                message(
                    "Outer",
                    &[
                        ("a", 1, Type::Double, None),
                        ("b", 2, Type::Uint64, None),
                        ("c", 3, Type::Int64, None),
                        ("d", 4, Type::String, None),
                        ("e", 5, Type::Double, None),
                        ("f", 6, Type::Message, Some(".t.Inner")),
                        ("g", 7, Type::Fixed32, None),
                    ],
                ),
                message(
                    "Inner",
                    &[
                        ("x", 1, Type::Double, None),
                        ("y", 2, Type::Message, Some(".t.Deeper")),
                    ],
                ),
                message("Deeper", &[("z", 1, Type::Uint64, None)]),
            ],
            ..Default::default()
        };
        let pool = DescriptorPool::from_file_descriptor_set(FileDescriptorSet { file: vec![file] })
            .unwrap();
        let desc = pool.get_message_by_name("t.Outer").unwrap();
        let m = DynamicMessage::decode(desc.clone(), e.buf.as_slice()).unwrap();
        let get = |m: &DynamicMessage, name: &str| m.get_field_by_name(name).unwrap().into_owned();
        assert_eq!(get(&m, "a"), Value::F64(293.15));
        assert_eq!(get(&m, "b"), Value::U64(300));
        assert_eq!(get(&m, "c"), Value::I64(-2));
        assert_eq!(get(&m, "d"), Value::String("eclipse entry".into()));
        assert_eq!(
            get(&m, "e"),
            Value::List(vec![Value::F64(1.0), Value::F64(-2.5)])
        );
        assert_eq!(get(&m, "g"), Value::U32(9));
        let Value::Message(inner) = get(&m, "f") else {
            panic!("f")
        };
        assert_eq!(get(&inner, "x"), Value::F64(7.0));
        let Value::Message(deeper) = get(&inner, "y") else {
            panic!("y")
        };
        assert_eq!(get(&deeper, "z"), Value::U64(5));
        // a length that runs past the end does not decode
        assert!(DynamicMessage::decode(desc, [0x22u8, 0x05, 1].as_slice()).is_err());
    }
}
