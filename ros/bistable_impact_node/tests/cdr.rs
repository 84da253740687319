//! The Rust message structs serialize to exactly the CDR bytes that rosidl's typesupport
//! produces: `tests/data/cdr_golden.json` holds field values and the bytes of
//! `rclpy.serialization.serialize_message` for them (checked against rclpy by
//! `tests/ros/test_cdr.py`, which also round-trips them through rclpy).

use bistable_impact_node::msg::{Clock, ImpactEvent, MassState, ShakerCommand};
use ros2_client::dds::rustdds::no_key::SerializerAdapter;
use ros2_client::dds::rustdds::CDRSerializerAdapter;
use serde::de::DeserializeOwned;
use serde::Serialize;

/// Encapsulation header of little-endian plain CDR, as rclpy writes it.
const CDR_LE: [u8; 4] = [0, 1, 0, 0];

fn cdr<T: Serialize>(value: &T) -> Vec<u8> {
    let body = CDRSerializerAdapter::<T>::to_bytes(value).unwrap();
    let mut out = CDR_LE.to_vec();
    out.extend_from_slice(&body);
    out
}

fn check<T: Serialize + DeserializeOwned + PartialEq + std::fmt::Debug>(
    fields: &serde_json::Value,
    hex: &str,
) -> usize {
    let value: T = serde_json::from_value(fields.clone()).unwrap();
    let bytes = cdr(&value);
    let got: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
    assert_eq!(got, hex, "{value:?}");
    let (back, used) = ros2_client::dds::rustdds::cdr_encoding::from_bytes::<
        T,
        byteorder::LittleEndian,
    >(&bytes[4..])
    .unwrap();
    assert_eq!(back, value);
    assert_eq!(used + 4, bytes.len());
    bytes.len()
}

#[test]
fn cdr_bytes_match_rosidl() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/cdr_golden.json"
    ))
    .unwrap();
    let cases: Vec<serde_json::Value> = serde_json::from_str(&text).unwrap();
    let mut types = Vec::new();
    for case in &cases {
        let (ty, fields, hex) = (
            case["type"].as_str().unwrap(),
            &case["fields"],
            case["cdr"].as_str().unwrap(),
        );
        let len = match ty {
            "MassState" => check::<MassState>(fields, hex),
            "ImpactEvent" => check::<ImpactEvent>(fields, hex),
            "ShakerCommand" => check::<ShakerCommand>(fields, hex),
            "Clock" => check::<Clock>(fields, hex),
            other => panic!("unknown type {other}"),
        };
        assert!(len > 4);
        types.push(ty);
    }
    assert_eq!(
        types,
        ["MassState", "ImpactEvent", "ShakerCommand", "Clock"]
    );
}
