//! A small PLY reader: ASCII and binary, vertex positions and face lists.

use std::path::Path;

use nalgebra::Point3;

use crate::error::{Result, SceneError};
use crate::mesh::TriangleMesh;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Format {
    Ascii,
    Little,
    Big,
}

#[derive(Clone, Copy, Debug)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Debug)]
enum Property {
    Scalar(String, Scalar),
    List(Scalar, Scalar),
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

/// Values come out of the body one at a time, from text words or binary bytes.
struct Body<'a> {
    format: Format,
    bytes: &'a [u8],
    pos: usize,
    words: std::str::SplitAsciiWhitespace<'a>,
}

impl Body<'_> {
    fn next(&mut self, t: Scalar) -> std::result::Result<f64, String> {
        if self.format == Format::Ascii {
            let w = self.words.next().ok_or("the body ends early")?;
            return w
                .parse::<f64>()
                .map_err(|_| format!("`{w}` is not a number"));
        }
        let n = t.size();
        let raw = self
            .bytes
            .get(self.pos..self.pos + n)
            .ok_or("the binary body ends early")?;
        self.pos += n;
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(raw);
        if self.format == Format::Big {
            b[..n].reverse();
        }
        Ok(match t {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }
}

/// The longest list (polygon) a face may hold.
const MAX_LIST: usize = 1 << 16;

pub(crate) fn parse(bytes: &[u8], path: &Path) -> Result<TriangleMesh> {
    let err = |line: usize, reason: String| SceneError::Parse {
        path: path.to_path_buf(),
        line,
        reason,
    };
    let mut pos = 0;
    let mut line_no = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .ok_or_else(|| err(line_no + 1, "the header has no `end_header`".into()))?;
        let line = std::str::from_utf8(&bytes[pos..pos + end])
            .map_err(|_| err(line_no + 1, "the header is not text".into()))?
            .trim();
        pos += end + 1;
        line_no += 1;
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["ply"] if line_no == 1 => {}
            _ if line_no == 1 => return Err(err(1, "not a PLY file (no `ply` magic)".into())),
            ["format", f, _] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    other => return Err(err(line_no, format!("unknown format `{other}`"))),
                })
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", name, count] => elements.push(Element {
                name: name.to_string(),
                count: count
                    .parse()
                    .map_err(|_| err(line_no, format!("bad element count `{count}`")))?,
                properties: Vec::new(),
            }),
            ["property", "list", c, t, _name] => {
                let (Some(c), Some(t)) = (Scalar::parse(c), Scalar::parse(t)) else {
                    return Err(err(line_no, format!("unknown list types in `{line}`")));
                };
                elements
                    .last_mut()
                    .ok_or_else(|| err(line_no, "a property before any element".into()))?
                    .properties
                    .push(Property::List(c, t));
            }
            ["property", t, name] => {
                let t = Scalar::parse(t)
                    .ok_or_else(|| err(line_no, format!("unknown property type `{t}`")))?;
                elements
                    .last_mut()
                    .ok_or_else(|| err(line_no, "a property before any element".into()))?
                    .properties
                    .push(Property::Scalar(name.to_string(), t));
            }
            ["end_header"] => break,
            _ => return Err(err(line_no, format!("unexpected header line `{line}`"))),
        }
    }
    let format = format.ok_or_else(|| err(0, "the header has no `format` line".into()))?;
    let text = if format == Format::Ascii {
        std::str::from_utf8(&bytes[pos..])
            .map_err(|_| err(0, "the ASCII body is not text".into()))?
    } else {
        ""
    };
    let mut body = Body {
        format,
        bytes,
        pos,
        words: text.split_ascii_whitespace(),
    };
    let mut mesh = TriangleMesh::default();
    for element in &elements {
        let xyz: Vec<Option<usize>> = ["x", "y", "z"]
            .iter()
            .map(|a| {
                element
                    .properties
                    .iter()
                    .position(|p| matches!(p, Property::Scalar(n, _) if n == a))
            })
            .collect();
        let is_vertex = element.name == "vertex";
        if is_vertex && xyz.iter().any(Option::is_none) {
            return Err(err(0, "the vertex element lacks x, y or z".into()));
        }
        let face_list = (element.name == "face")
            .then(|| {
                element
                    .properties
                    .iter()
                    .position(|p| matches!(p, Property::List(..)))
            })
            .flatten();
        // An element without properties takes no bytes: its count, however large, reads
        // nothing (and must not be looped over).
        if element.properties.is_empty() {
            continue;
        }
        for item in 0..element.count {
            let mut point = [0.0f32; 3];
            for (k, property) in element.properties.iter().enumerate() {
                let where_ = |e: String| err(0, format!("{} {item}: {e}", element.name));
                match property {
                    Property::Scalar(_, t) => {
                        let v = body.next(*t).map_err(where_)?;
                        if let Some(axis) = xyz.iter().position(|&a| a == Some(k)) {
                            point[axis] = v as f32;
                        }
                    }
                    Property::List(c, t) => {
                        // A list's length is read from the file: check it before trusting
                        // it with memory (a float length or a huge one is an error).
                        let len = body.next(*c).map_err(where_)?;
                        if !(len >= 0.0 && len.fract() == 0.0 && len <= MAX_LIST as f64) {
                            return Err(err(
                                0,
                                format!("{} {item}: bad list length {len}", element.name),
                            ));
                        }
                        let n = len as usize;
                        let mut idx = Vec::with_capacity(n.min(16));
                        for _ in 0..n {
                            let v = body.next(*t).map_err(where_)?;
                            if !(v >= 0.0 && v.fract() == 0.0 && v <= u32::MAX as f64) {
                                return Err(err(0, format!("face {item}: bad vertex index {v}")));
                            }
                            idx.push(v as u32);
                        }
                        if face_list == Some(k) {
                            if n < 3 {
                                return Err(err(0, format!("face {item} has {n} vertices")));
                            }
                            for j in 1..n - 1 {
                                mesh.triangles.push([idx[0], idx[j], idx[j + 1]]);
                            }
                        }
                    }
                }
            }
            if is_vertex {
                mesh.vertices.push(Point3::from(point));
            }
        }
    }
    mesh.validate(&path.display().to_string())?;
    Ok(mesh)
}
