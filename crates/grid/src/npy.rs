//! `.npy` input/output (NumPy format 1.0 to write; 1.0-3.0 to read), readable by `numpy.load`.

use crate::io::write_atomic;
use crate::{Field2, Field3, Grid2, Grid3, GridError, Result};
use std::path::Path;

/// The element data of an `.npy` array.
#[derive(Clone, Debug, PartialEq)]
pub enum NpyData {
    /// `|b1`
    Bool(Vec<bool>),
    /// `|u1`
    U8(Vec<u8>),
    /// `<f4`
    F32(Vec<f32>),
    /// `<f8`
    F64(Vec<f64>),
}

impl NpyData {
    fn len(&self) -> usize {
        match self {
            NpyData::Bool(v) => v.len(),
            NpyData::U8(v) => v.len(),
            NpyData::F32(v) => v.len(),
            NpyData::F64(v) => v.len(),
        }
    }

    fn descr(&self) -> &'static str {
        match self {
            NpyData::Bool(_) => "|b1",
            NpyData::U8(_) => "|u1",
            NpyData::F32(_) => "<f4",
            NpyData::F64(_) => "<f8",
        }
    }
}

/// A C-order array read from or written to `.npy`.
#[derive(Clone, Debug, PartialEq)]
pub struct NpyArray {
    /// The array's shape.
    pub shape: Vec<usize>,
    /// Its elements in C order.
    pub data: NpyData,
}

const MAGIC: &[u8] = b"\x93NUMPY";

fn err(msg: impl Into<String>) -> GridError {
    GridError::Npy(msg.into())
}

impl NpyArray {
    /// Encodes the array as `.npy` bytes (format version 1.0).
    ///
    /// # Errors
    /// [`GridError::Npy`] when the shape does not match the data length.
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        let n: usize = self.shape.iter().product();
        if n != self.data.len() {
            return Err(err(format!(
                "shape {:?} holds {n} elements but the data has {}",
                self.shape,
                self.data.len()
            )));
        }
        let shape = match self.shape.len() {
            1 => format!("({},)", self.shape[0]),
            _ => format!(
                "({})",
                self.shape
                    .iter()
                    .map(|d| d.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        let mut header = format!(
            "{{'descr': '{}', 'fortran_order': False, 'shape': {shape}, }}",
            self.data.descr()
        );
        // Pad so that the data starts on a 64-byte boundary; the header ends with a newline.
        let unpadded = MAGIC.len() + 2 + 2 + header.len() + 1;
        header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
        header.push('\n');
        let mut out = Vec::with_capacity(MAGIC.len() + 4 + header.len() + n * 8);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&[1, 0]);
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        match &self.data {
            NpyData::Bool(v) => out.extend(v.iter().map(|&b| b as u8)),
            NpyData::U8(v) => out.extend_from_slice(v),
            NpyData::F32(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            NpyData::F64(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
        }
        Ok(out)
    }

    /// Decodes `.npy` bytes.
    ///
    /// # Errors
    /// [`GridError::Npy`] for a bad magic string, an unsupported version, dtype or Fortran
    /// order, a malformed header, or data shorter or longer than the shape says.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        if bytes.len() < 10 || &bytes[..6] != MAGIC {
            return Err(err("not an .npy file (bad magic string)"));
        }
        let (major, minor) = (bytes[6], bytes[7]);
        let (hlen, start) = match major {
            1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
            2 | 3 if bytes.len() >= 12 => (
                u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
                12,
            ),
            _ => return Err(err(format!("unsupported format version {major}.{minor}"))),
        };
        let header = bytes
            .get(start..start + hlen)
            .ok_or_else(|| err("file ends inside the header"))?;
        let header = std::str::from_utf8(header).map_err(|_| err("header is not text"))?;
        let descr = dict_value(header, "descr")?;
        let descr = descr.trim().trim_matches(|c| c == '\'' || c == '"');
        let fortran = dict_value(header, "fortran_order")?;
        if fortran.trim() != "False" {
            return Err(err(
                "Fortran-order arrays are not supported (save a C-order array, e.g. np.ascontiguousarray)",
            ));
        }
        let shape_text = dict_value(header, "shape")?;
        let shape_text = shape_text
            .trim()
            .trim_start_matches('(')
            .trim_end_matches(')');
        let shape: Vec<usize> = shape_text
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(|s| s.parse().map_err(|_| err(format!("bad shape entry {s:?}"))))
            .collect::<Result<_>>()?;
        let n = shape
            .iter()
            .try_fold(1usize, |a, &d| a.checked_mul(d))
            .ok_or_else(|| err(format!("shape {shape:?} overflows")))?;
        let body = &bytes[start + hlen..];
        let width = match descr {
            "|b1" | "|u1" | "<u1" => 1,
            "<f4" => 4,
            "<f8" => 8,
            other => {
                return Err(err(format!(
                    "unsupported dtype {other:?} (expected bool, uint8, little-endian float32 or float64)"
                )))
            }
        };
        if body.len() != n * width {
            return Err(err(format!(
                "shape {shape:?} of {descr} needs {} data bytes, the file has {} (truncated or corrupt)",
                n * width,
                body.len()
            )));
        }
        let data = match descr {
            "|b1" => NpyData::Bool(body.iter().map(|&b| b != 0).collect()),
            "<f4" => NpyData::F32(
                body.chunks_exact(4)
                    .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                    .collect(),
            ),
            "<f8" => NpyData::F64(
                body.chunks_exact(8)
                    .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
                    .collect(),
            ),
            _ => NpyData::U8(body.to_vec()),
        };
        Ok(Self { shape, data })
    }

    /// Reads an `.npy` file.
    ///
    /// # Errors
    /// [`GridError::Io`] or the errors of [`NpyArray::from_bytes`] (prefixed with the path).
    pub fn read(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|e| GridError::io(path, e))?;
        Self::from_bytes(&bytes).map_err(|e| named(path, e))
    }

    /// Writes an `.npy` file atomically.
    ///
    /// # Errors
    /// [`GridError::Io`] or [`GridError::Npy`].
    pub fn write(&self, path: impl AsRef<Path>) -> Result<()> {
        write_atomic(path, &self.to_bytes()?)
    }

    fn obstacle_mask(self, ndim: usize) -> Result<(Vec<usize>, Vec<bool>)> {
        if self.shape.len() != ndim {
            return Err(err(format!(
                "expected a {ndim}D array for a grid, found shape {:?}",
                self.shape
            )));
        }
        let mask = match self.data {
            NpyData::Bool(v) => v,
            NpyData::U8(v) => v.into_iter().map(|b| b != 0).collect(),
            NpyData::F32(_) | NpyData::F64(_) => {
                return Err(err(
                    "a grid must be a bool or uint8 array (nonzero = obstacle)",
                ))
            }
        };
        Ok((self.shape, mask))
    }

    fn values(self, ndim: usize) -> Result<(Vec<usize>, Vec<f32>)> {
        if self.shape.len() != ndim {
            return Err(err(format!(
                "expected a {ndim}D array for a field, found shape {:?}",
                self.shape
            )));
        }
        let values = match self.data {
            NpyData::F32(v) => v,
            NpyData::F64(v) => v.into_iter().map(|x| x as f32).collect(),
            _ => return Err(err("a field must be a float32 or float64 array")),
        };
        Ok((self.shape, values))
    }
}

fn dict_value<'a>(header: &'a str, key: &str) -> Result<&'a str> {
    let pat_a = format!("'{key}':");
    let pat_b = format!("\"{key}\":");
    let at = header
        .find(&pat_a)
        .map(|i| i + pat_a.len())
        .or_else(|| header.find(&pat_b).map(|i| i + pat_b.len()))
        .ok_or_else(|| err(format!("header has no {key:?} entry")))?;
    let rest = &header[at..];
    let end = if rest.trim_start().starts_with('(') {
        rest.find(')').map(|i| i + 1)
    } else {
        rest.find([',', '}'])
    }
    .ok_or_else(|| err(format!("malformed {key:?} entry in header")))?;
    Ok(&rest[..end])
}

impl Grid2 {
    /// Reads a grid from a 2D bool or uint8 `.npy` array (nonzero = obstacle).
    ///
    /// # Errors
    /// [`GridError::Io`] or [`GridError::Npy`].
    pub fn read_npy(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let (shape, mask) = NpyArray::read(path)?
            .obstacle_mask(2)
            .map_err(|e| named(path, e))?;
        Grid2::from_obstacles(shape[0], shape[1], mask)
    }

    /// Writes the grid as a 2D bool `.npy` array (`True` = obstacle), atomically.
    ///
    /// # Errors
    /// [`GridError::Io`].
    pub fn write_npy(&self, path: impl AsRef<Path>) -> Result<()> {
        NpyArray {
            shape: vec![self.rows(), self.cols()],
            data: NpyData::Bool(self.obstacles().to_vec()),
        }
        .write(path)
    }
}

impl Grid3 {
    /// Reads a grid from a 3D bool or uint8 `.npy` array (nonzero = obstacle).
    ///
    /// # Errors
    /// [`GridError::Io`] or [`GridError::Npy`].
    pub fn read_npy(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let (shape, mask) = NpyArray::read(path)?
            .obstacle_mask(3)
            .map_err(|e| named(path, e))?;
        Grid3::from_obstacles([shape[0], shape[1], shape[2]], mask)
    }

    /// Writes the grid as a 3D bool `.npy` array, atomically.
    ///
    /// # Errors
    /// [`GridError::Io`].
    pub fn write_npy(&self, path: impl AsRef<Path>) -> Result<()> {
        NpyArray {
            shape: self.shape().to_vec(),
            data: NpyData::Bool(self.obstacles().to_vec()),
        }
        .write(path)
    }
}

impl Field2 {
    /// Reads a field from a 2D float32 (or float64) `.npy` array.
    ///
    /// # Errors
    /// [`GridError::Io`] or [`GridError::Npy`].
    pub fn read_npy(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let (shape, values) = NpyArray::read(path)?
            .values(2)
            .map_err(|e| named(path, e))?;
        Field2::new(shape[0], shape[1], values)
    }

    /// Writes the field as a 2D float32 `.npy` array (infinity stays `inf`), atomically.
    ///
    /// # Errors
    /// [`GridError::Io`].
    pub fn write_npy(&self, path: impl AsRef<Path>) -> Result<()> {
        NpyArray {
            shape: vec![self.rows(), self.cols()],
            data: NpyData::F32(self.values().to_vec()),
        }
        .write(path)
    }
}

impl Field3 {
    /// Reads a field from a 3D float32 (or float64) `.npy` array.
    ///
    /// # Errors
    /// [`GridError::Io`] or [`GridError::Npy`].
    pub fn read_npy(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let (shape, values) = NpyArray::read(path)?
            .values(3)
            .map_err(|e| named(path, e))?;
        Field3::new([shape[0], shape[1], shape[2]], values)
    }

    /// Writes the field as a 3D float32 `.npy` array, atomically.
    ///
    /// # Errors
    /// [`GridError::Io`].
    pub fn write_npy(&self, path: impl AsRef<Path>) -> Result<()> {
        NpyArray {
            shape: self.shape().to_vec(),
            data: NpyData::F32(self.values().to_vec()),
        }
        .write(path)
    }
}

/// `e` with the file it concerns in its message.
fn named(path: &Path, e: GridError) -> GridError {
    match e {
        GridError::Npy(m) => GridError::Npy(format!("{}: {m}", path.display())),
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_aligns_the_header() {
        for data in [
            NpyData::Bool(vec![true, false, false, true, true, false]),
            NpyData::U8(vec![0, 1, 2, 3, 4, 5]),
            NpyData::F32(vec![0.5, f32::INFINITY, -1.0, 2.0, 3.0, 4.0]),
            NpyData::F64(vec![0.5, 1.0, -1.0, 2.0, 3.0, 4.0]),
        ] {
            let a = NpyArray {
                shape: vec![2, 3],
                data,
            };
            let bytes = a.to_bytes().unwrap();
            let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
            assert_eq!((10 + header_len) % 64, 0);
            assert_eq!(NpyArray::from_bytes(&bytes).unwrap(), a);
        }
    }

    #[test]
    fn rejects_truncated_and_foreign_data() {
        let a = NpyArray {
            shape: vec![4, 4],
            data: NpyData::F32(vec![1.0; 16]),
        };
        let bytes = a.to_bytes().unwrap();
        let e = NpyArray::from_bytes(&bytes[..bytes.len() - 3]).unwrap_err();
        assert!(e.to_string().contains("truncated"), "{e}");
        assert!(NpyArray::from_bytes(b"PK\x03\x04 not numpy").is_err());
        let wrong = a.clone().obstacle_mask(2).unwrap_err();
        assert!(wrong.to_string().contains("bool or uint8"), "{wrong}");
        assert!(a.values(3).is_err());
    }

    #[test]
    fn reads_a_header_written_by_numpy() {
        // np.save of np.zeros((2, 3), dtype=np.float32) with numpy 2.x: version 1.0, header
        // padded to 128 bytes in total.
        let mut header =
            String::from("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }");
        while (10 + header.len() + 1) % 64 != 0 {
            header.push(' ');
        }
        header.push('\n');
        let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
        bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
        bytes.extend_from_slice(header.as_bytes());
        bytes.extend_from_slice(&[0u8; 24]);
        let a = NpyArray::from_bytes(&bytes).unwrap();
        assert_eq!(a.shape, vec![2, 3]);
        assert_eq!(a.data, NpyData::F32(vec![0.0; 6]));
    }
}
