//! Protobuf schemas of the log's own messages, built at run time (node, load and gear
//! names become field names, so every series is readable by name in Foxglove and
//! Rerun) and stored in the MCAP file as `FileDescriptorSet`s. Foxglove's well-known
//! types (`foxglove.Log`, `foxglove.SceneUpdate`) come from the official `foxglove`
//! crate instead.

use prost::Message;
use prost_types::field_descriptor_proto::{Label, Type};
use prost_types::{DescriptorProto, FieldDescriptorProto, FileDescriptorProto, FileDescriptorSet};

/// A field of a message being described.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    pub name: String,
    pub number: u32,
    pub kind: Kind,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Kind {
    Double,
    RepeatedDouble,
    /// A message type of the same package, by short name.
    Message(String),
}

/// A message type: short name and fields.
#[derive(Debug, Clone, PartialEq)]
pub struct MessageType {
    pub name: String,
    pub fields: Vec<Field>,
}

impl MessageType {
    pub fn new(name: &str) -> MessageType {
        MessageType {
            name: name.to_string(),
            fields: vec![],
        }
    }

    /// Appends a field numbered after the last one.
    pub fn with(mut self, name: &str, kind: Kind) -> MessageType {
        let number = self.fields.len() as u32 + 1;
        self.fields.push(Field {
            name: name.to_string(),
            number,
            kind,
        });
        self
    }
}

pub const PACKAGE: &str = "orbitlash";

/// Seconds to MCAP nanoseconds (never negative).
pub(crate) fn ns(t_s: f64) -> u64 {
    (t_s * 1e9).round().max(0.0) as u64
}

pub use crate::units::identifier;

fn field(f: &Field) -> FieldDescriptorProto {
    let (ty, label, type_name) = match &f.kind {
        Kind::Double => (Type::Double, Label::Optional, None),
        Kind::RepeatedDouble => (Type::Double, Label::Repeated, None),
        Kind::Message(m) => (
            Type::Message,
            Label::Optional,
            Some(format!(".{PACKAGE}.{m}")),
        ),
    };
    FieldDescriptorProto {
        name: Some(f.name.clone()),
        number: Some(f.number as i32),
        label: Some(label as i32),
        r#type: Some(ty as i32),
        type_name,
        json_name: Some(f.name.clone()),
        ..Default::default()
    }
}

/// The encoded `FileDescriptorSet` of `types` (the first is the channel's message).
pub fn descriptor_set(file_name: &str, types: &[MessageType]) -> Vec<u8> {
    let file = FileDescriptorProto {
        name: Some(format!("{PACKAGE}/{file_name}.proto")),
        package: Some(PACKAGE.into()),
        message_type: types
            .iter()
            .map(|t| DescriptorProto {
                name: Some(t.name.clone()),
                field: t.fields.iter().map(field).collect(),
                ..Default::default()
            })
            .collect(),
        syntax: Some("proto3".into()),
        ..Default::default()
    };
    FileDescriptorSet { file: vec![file] }.encode_to_vec()
}
