//! The element types a field can have (its own module so that the error
//! type can name one without depending on the snapshot model).

/// Element type of a field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FieldType {
    /// 64-bit IEEE float.
    F64,
    /// 64-bit unsigned integer (particle ids, keys).
    U64,
}

impl std::fmt::Display for FieldType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FieldType::F64 => "f64",
            FieldType::U64 => "u64",
        })
    }
}
