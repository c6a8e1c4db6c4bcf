//! Protobuf schemas of the log's messages, built at run time (node, load and gear
//! names become field names, so every series is readable by name in Foxglove and
//! Rerun) and stored in the MCAP file as `FileDescriptorSet`s.

use prost::Message;
use prost_types::field_descriptor_proto::{Label, Type};
use prost_types::{
    DescriptorProto, EnumDescriptorProto, EnumValueDescriptorProto, FieldDescriptorProto,
    FileDescriptorProto, FileDescriptorSet,
};

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

/// A field name made of ASCII letters, digits and `_`, not starting with a digit.
pub fn identifier(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect();
    if s.chars().next().is_none_or(|c| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    s
}

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

/// `foxglove.Log` (foxglove/schemas, `Log.proto`) with `google.protobuf.Timestamp`.
pub fn foxglove_log_descriptor_set() -> Vec<u8> {
    use Type::{Enum, Fixed32, Message, String as Str};
    let mut log = fox_message(
        "Log",
        &[
            (
                "timestamp",
                1,
                Message,
                false,
                Some(".google.protobuf.Timestamp"),
            ),
            ("level", 2, Enum, false, Some(".foxglove.Log.Level")),
            ("message", 3, Str, false, None),
            ("name", 4, Str, false, None),
            ("file", 5, Str, false, None),
            ("line", 6, Fixed32, false, None),
        ],
    );
    log.enum_type.push(enum_type(
        "Level",
        &["UNKNOWN", "DEBUG", "INFO", "WARNING", "ERROR", "FATAL"],
    ));
    FileDescriptorSet {
        file: vec![
            google_time_file(),
            proto_file("foxglove/Log.proto", "foxglove", &[GOOGLE_TIME], vec![log]),
        ],
    }
    .encode_to_vec()
}

/// A field of a foxglove schema: (name, number, type, repeated, message type).
type FoxField = (&'static str, i32, Type, bool, Option<&'static str>);

fn fox_message(name: &str, fields: &[FoxField]) -> DescriptorProto {
    DescriptorProto {
        name: Some(name.into()),
        field: fields
            .iter()
            .map(|&(n, num, ty, repeated, type_name)| FieldDescriptorProto {
                name: Some(n.into()),
                number: Some(num),
                label: Some(if repeated {
                    Label::Repeated
                } else {
                    Label::Optional
                } as i32),
                r#type: Some(ty as i32),
                type_name: type_name.map(Into::into),
                json_name: Some(n.into()),
                ..Default::default()
            })
            .collect(),
        ..Default::default()
    }
}

/// `foxglove.SceneUpdate` as far as line primitives go (the field numbers of
/// foxglove's schemas; fields this crate does not write are left out, which protobuf
/// decoders ignore).
pub fn foxglove_scene_descriptor_set() -> Vec<u8> {
    use Type::{Bool, Double, Enum, Message, String as Str};
    let xyz = |extra: Option<FoxField>| {
        let mut v = vec![
            ("x", 1, Double, false, None),
            ("y", 2, Double, false, None),
            ("z", 3, Double, false, None),
        ];
        v.extend(extra);
        v
    };
    let mut line = fox_message(
        "LinePrimitive",
        &[
            ("type", 1, Enum, false, Some(".foxglove.LinePrimitive.Type")),
            ("pose", 2, Message, false, Some(".foxglove.Pose")),
            ("thickness", 3, Double, false, None),
            ("scale_invariant", 4, Bool, false, None),
            ("points", 5, Message, true, Some(".foxglove.Point3")),
            ("color", 6, Message, false, Some(".foxglove.Color")),
        ],
    );
    line.enum_type
        .push(enum_type("Type", &["LINE_STRIP", "LINE_LOOP", "LINE_LIST"]));
    let foxglove = proto_file(
        "foxglove/SceneUpdate.proto",
        "foxglove",
        &[GOOGLE_TIME],
        vec![
            fox_message("Vector3", &xyz(None)),
            fox_message("Point3", &xyz(None)),
            fox_message("Quaternion", &xyz(Some(("w", 4, Double, false, None)))),
            fox_message(
                "Color",
                &[
                    ("r", 1, Double, false, None),
                    ("g", 2, Double, false, None),
                    ("b", 3, Double, false, None),
                    ("a", 4, Double, false, None),
                ],
            ),
            fox_message(
                "Pose",
                &[
                    ("position", 1, Message, false, Some(".foxglove.Vector3")),
                    (
                        "orientation",
                        2,
                        Message,
                        false,
                        Some(".foxglove.Quaternion"),
                    ),
                ],
            ),
            line,
            fox_message(
                "SceneEntity",
                &[
                    (
                        "timestamp",
                        1,
                        Message,
                        false,
                        Some(".google.protobuf.Timestamp"),
                    ),
                    ("frame_id", 2, Str, false, None),
                    ("id", 3, Str, false, None),
                    (
                        "lifetime",
                        4,
                        Message,
                        false,
                        Some(".google.protobuf.Duration"),
                    ),
                    ("frame_locked", 5, Bool, false, None),
                    ("lines", 11, Message, true, Some(".foxglove.LinePrimitive")),
                ],
            ),
            fox_message(
                "SceneUpdate",
                &[("entities", 2, Message, true, Some(".foxglove.SceneEntity"))],
            ),
        ],
    );
    FileDescriptorSet {
        file: vec![google_time_file(), foxglove],
    }
    .encode_to_vec()
}

/// An enum type whose values are numbered in order.
fn enum_type(name: &str, values: &[&str]) -> EnumDescriptorProto {
    EnumDescriptorProto {
        name: Some(name.into()),
        value: values
            .iter()
            .enumerate()
            .map(|(i, n)| EnumValueDescriptorProto {
                name: Some((*n).into()),
                number: Some(i as i32),
                ..Default::default()
            })
            .collect(),
        ..Default::default()
    }
}

fn proto_file(
    name: &str,
    package: &str,
    deps: &[&str],
    messages: Vec<DescriptorProto>,
) -> FileDescriptorProto {
    FileDescriptorProto {
        name: Some(name.into()),
        package: Some(package.into()),
        dependency: deps.iter().map(|d| (*d).into()).collect(),
        message_type: messages,
        syntax: Some("proto3".into()),
        ..Default::default()
    }
}

const GOOGLE_TIME: &str = "google/protobuf/time.proto";

/// `google.protobuf.Timestamp` and `Duration` (same wire form: seconds, nanos).
fn google_time_file() -> FileDescriptorProto {
    use Type::{Int32, Int64};
    let time = |name: &str| {
        fox_message(
            name,
            &[
                ("seconds", 1, Int64, false, None),
                ("nanos", 2, Int32, false, None),
            ],
        )
    };
    proto_file(
        GOOGLE_TIME,
        "google.protobuf",
        &[],
        vec![time("Timestamp"), time("Duration")],
    )
}
