//! A read position in a file that mixes text and binary (gmsh `.msh`, legacy `.vtk`, medit
//! `.mesh`): whitespace-separated words, whole lines, and little- or big-endian numbers. Every
//! error names the file and the line (text) or byte offset (binary); counts read from headers are
//! checked against the bytes left before anything is allocated for them.

use std::path::Path;
use std::str::FromStr;

use crate::MeshError;

/// A numeric type a binary array may hold, by its size and kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Scalar {
    /// The VTK XML `type` attribute (`Int32`, `Float64`, ...).
    pub(super) fn from_vtk_xml(name: &str) -> Option<Self> {
        Some(match name {
            "Int8" => Self::I8,
            "UInt8" => Self::U8,
            "Int16" => Self::I16,
            "UInt16" => Self::U16,
            "Int32" => Self::I32,
            "UInt32" => Self::U32,
            "Int64" => Self::I64,
            "UInt64" => Self::U64,
            "Float32" => Self::F32,
            "Float64" => Self::F64,
            _ => return None,
        })
    }

    /// A legacy VTK data type (`float`, `vtktypeint64`, ...).
    pub(super) fn from_vtk_legacy(name: &str) -> Option<Self> {
        Some(match name.to_ascii_lowercase().as_str() {
            "char" => Self::I8,
            "unsigned_char" => Self::U8,
            "short" => Self::I16,
            "unsigned_short" => Self::U16,
            "int" | "vtktypeint32" => Self::I32,
            "unsigned_int" | "vtktypeuint32" => Self::U32,
            "long" | "vtkidtype" | "vtktypeint64" => Self::I64,
            "unsigned_long" | "vtktypeuint64" => Self::U64,
            "float" => Self::F32,
            "double" => Self::F64,
            _ => return None,
        })
    }

    pub(super) fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::I64 | Self::U64 | Self::F64 => 8,
        }
    }

    /// Decodes `bytes` (a whole number of values) into f64s; 64-bit integers above 2^53 lose
    /// precision, which no index or count of a mesh that fits in memory reaches.
    pub(super) fn decode(self, bytes: &[u8], big_endian: bool) -> Vec<f64> {
        bytes.chunks_exact(self.size()).map(|b| self.decode_one(b, big_endian)).collect()
    }

    /// Decodes one value from exactly `self.size()` bytes.
    fn decode_one(self, b: &[u8], big_endian: bool) -> f64 {
        macro_rules! one {
            ($t:ty) => {{
                let b = b.try_into().expect("the caller passes exactly one value");
                (if big_endian { <$t>::from_be_bytes(b) } else { <$t>::from_le_bytes(b) }) as f64
            }};
        }
        match self {
            Self::I8 => one!(i8),
            Self::U8 => one!(u8),
            Self::I16 => one!(i16),
            Self::U16 => one!(u16),
            Self::I32 => one!(i32),
            Self::U32 => one!(u32),
            Self::I64 => one!(i64),
            Self::U64 => one!(u64),
            Self::F32 => one!(f32),
            Self::F64 => one!(f64),
        }
    }
}

/// A number a writer stores in binary: its VTK XML and legacy type names and its bytes.
pub(super) trait Number: Copy + std::fmt::Debug {
    const VTK: &'static str;
    const LEGACY: &'static str;
    fn put(self, big_endian: bool, out: &mut Vec<u8>);
}

macro_rules! number {
    ($t:ty, $vtk:literal, $legacy:literal) => {
        impl Number for $t {
            const VTK: &'static str = $vtk;
            const LEGACY: &'static str = $legacy;
            fn put(self, big_endian: bool, out: &mut Vec<u8>) {
                out.extend_from_slice(&if big_endian { self.to_be_bytes() } else { self.to_le_bytes() });
            }
        }
    };
}
number!(u8, "UInt8", "unsigned_char");
number!(i32, "Int32", "int");
number!(i64, "Int64", "vtktypeint64");
number!(f64, "Float64", "double");

/// A value read as f64 that must be a vertex index; `None` when it is not one.
pub(super) fn as_index(x: f64) -> Option<u32> {
    (x >= 0.0 && x <= f64::from(u32::MAX) && x.fract() == 0.0).then_some(x as u32)
}

pub(super) struct Cursor<'a> {
    pub(super) path: &'a Path,
    bytes: &'a [u8],
    pub(super) pos: usize,
    pub(super) big_endian: bool,
}

impl<'a> Cursor<'a> {
    pub(super) fn new(path: &'a Path, bytes: &'a [u8]) -> Self {
        Self { path, bytes, pos: 0, big_endian: false }
    }

    /// The bytes not yet read.
    pub(super) fn rest(&self) -> &'a [u8] {
        &self.bytes[self.pos..]
    }

    /// A text error at the current line (1-based; counted only when an error is made).
    pub(super) fn error(&self, message: impl Into<String>) -> MeshError {
        let line = 1 + self.bytes[..self.pos].iter().filter(|&&b| b == b'\n').count();
        MeshError::Parse { path: self.path.to_owned(), line, message: message.into() }
    }

    /// A binary error at the current byte offset.
    pub(super) fn byte_error(&self, message: impl Into<String>) -> MeshError {
        MeshError::AtByte { path: self.path.to_owned(), offset: self.pos, message: message.into() }
    }

    fn skip_whitespace(&mut self) {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    /// The rest of the current line without its line ending, or `None` at the end of the file.
    pub(super) fn line(&mut self) -> Result<Option<&'a str>, MeshError> {
        if self.pos == self.bytes.len() {
            return Ok(None);
        }
        let rest = self.rest();
        let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        let line = rest[..end].strip_suffix(b"\r").unwrap_or(&rest[..end]);
        let text = std::str::from_utf8(line).map_err(|_| self.error("not a text line (binary data?)"))?;
        self.pos += (end + 1).min(rest.len());
        Ok(Some(text))
    }

    /// The next line, which must exist.
    pub(super) fn expect_line(&mut self, what: &str) -> Result<&'a str, MeshError> {
        self.line()?.ok_or_else(|| self.error(format!("unexpected end of file, expected {what}")))
    }

    /// The next whitespace-separated word, or `None` at the end of the file.
    pub(super) fn word(&mut self) -> Result<Option<&'a str>, MeshError> {
        self.skip_whitespace();
        let rest = self.rest();
        let len = rest.iter().position(|b| b.is_ascii_whitespace()).unwrap_or(rest.len());
        if len == 0 {
            return Ok(None);
        }
        let word = std::str::from_utf8(&rest[..len]).map_err(|_| self.error("not text (binary data?)"))?;
        self.pos += len;
        Ok(Some(word))
    }

    /// The next word, which must exist.
    pub(super) fn expect_word(&mut self, what: &str) -> Result<&'a str, MeshError> {
        self.word()?.ok_or_else(|| self.error(format!("unexpected end of file, expected {what}")))
    }

    /// Parses the next word.
    pub(super) fn parse<T: FromStr>(&mut self, what: &str) -> Result<T, MeshError> {
        let word = self.expect_word(what)?;
        word.parse().map_err(|_| self.error(format!("bad {what} `{word}`")))
    }

    /// Parses the next word as a finite number.
    pub(super) fn real(&mut self, what: &str) -> Result<f64, MeshError> {
        let x: f64 = self.parse(what)?;
        if x.is_finite() { Ok(x) } else { Err(self.error(format!("{what} is not finite"))) }
    }

    /// Checks that `count` items of at least `min_bytes` each can still follow, so that a
    /// corrupt header never makes a reader allocate more than the file could hold.
    pub(super) fn bound(&self, count: u64, min_bytes: usize, what: &str) -> Result<usize, MeshError> {
        let left = self.bytes.len() - self.pos;
        match usize::try_from(count) {
            Ok(n) if n.checked_mul(min_bytes).is_some_and(|b| b <= left) => Ok(n),
            _ => Err(self.error(format!("{count} {what} announced, but only {left} bytes are left"))),
        }
    }

    /// Skips through the end of the current line: binary data starts right after it.
    pub(super) fn skip_line(&mut self) {
        let rest = self.rest();
        self.pos += rest.iter().position(|&b| b == b'\n').map_or(rest.len(), |i| i + 1);
    }

    /// The next `n` raw bytes.
    pub(super) fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], MeshError> {
        let left = self.bytes.len() - self.pos;
        if n > left {
            return Err(self.byte_error(format!("truncated: {what} needs {n} bytes, {left} are left")));
        }
        self.pos += n;
        Ok(&self.bytes[self.pos - n..self.pos])
    }

    /// `count` binary values of type `ty` in the cursor's byte order.
    pub(super) fn values(&mut self, ty: Scalar, count: usize, what: &str) -> Result<Vec<f64>, MeshError> {
        let n = count.checked_mul(ty.size()).ok_or_else(|| self.byte_error(format!("{what}: too many values")))?;
        let big_endian = self.big_endian;
        Ok(ty.decode(self.take(n, what)?, big_endian))
    }

    /// One binary value of type `ty`.
    pub(super) fn value(&mut self, ty: Scalar, what: &str) -> Result<f64, MeshError> {
        let big_endian = self.big_endian;
        Ok(ty.decode_one(self.take(ty.size(), what)?, big_endian))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_lines_and_binary_values_with_positions_in_errors() {
        let bytes = b"  12 abc\r\nnext line\n\x01\x00\x00\x00\x00\x00\xf0\x3f";
        let mut c = Cursor::new(Path::new("f"), bytes);
        assert_eq!(c.parse::<u32>("n").unwrap(), 12);
        assert_eq!(c.line().unwrap(), Some(" abc"));
        assert_eq!(c.expect_line("x").unwrap(), "next line");
        assert_eq!(c.value(Scalar::I32, "one").unwrap(), 1.0);
        assert_eq!(c.values(Scalar::F32, 1, "x").unwrap(), vec![1.875]);
        let err = c.take(1, "more").unwrap_err().to_string();
        assert_eq!(err, "f: byte 28: truncated: more needs 1 bytes, 0 are left");
        let mut c = Cursor::new(Path::new("f"), b"1\n2\nx");
        c.word().unwrap();
        c.word().unwrap();
        assert_eq!(c.parse::<f64>("y").unwrap_err().to_string(), "f:3: bad y `x`");
        assert!(c.bound(1, 1, "nodes").unwrap_err().to_string().contains("1 nodes announced"));
        assert_eq!(as_index(3.0), Some(3));
        assert_eq!(as_index(-1.0), None);
        assert_eq!(as_index(0.5), None);
    }
}
