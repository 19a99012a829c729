//! PNG input (occupancy grids) and output (heat maps of fields with paths).

use crate::io::write_atomic;
use crate::{viridis, Cell2, Field2, Grid2, GridError, Result};
use image::{Rgb, RgbImage};
use std::path::Path;

/// The most pixels [`Grid2::from_png_bytes`] decodes (16384 x 16384).
pub const MAX_PNG_PIXELS: u64 = 1 << 28;

/// Decoder limits that bound the memory an image may claim.
fn limits_for_grids() -> image::Limits {
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(8 * MAX_PNG_PIXELS);
    limits
}

impl Grid2 {
    /// Reads a grid from an image: pixels darker than mid-grey (luma < 128) are obstacles, one
    /// pixel a cell.
    ///
    /// # Errors
    /// [`GridError::Io`]; [`GridError::Invalid`] naming the file for one that is not a readable
    /// image or holds more than [`MAX_PNG_PIXELS`] pixels.
    pub fn read_png(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|e| GridError::io(path, e))?;
        Self::from_png_bytes(&bytes, path)
    }

    /// Decodes image bytes as [`Grid2::read_png`] does; `source` names them in errors. The
    /// size is read from the header and checked before any pixel is decoded.
    ///
    /// # Errors
    /// [`GridError::Invalid`] naming `source` for bytes that are not a readable image, or an
    /// image of more than [`MAX_PNG_PIXELS`] pixels.
    pub fn from_png_bytes(bytes: &[u8], source: impl AsRef<Path>) -> Result<Self> {
        let path = source.as_ref();
        let bad =
            |e: String| GridError::Invalid(format!("{}: not a readable PNG: {e}", path.display()));
        let reader = || -> Result<_> {
            let mut r = image::ImageReader::new(std::io::Cursor::new(bytes))
                .with_guessed_format()
                .map_err(|e| bad(e.to_string()))?;
            r.limits(limits_for_grids());
            Ok(r)
        };
        let (w, h) = reader()?
            .into_dimensions()
            .map_err(|e| bad(e.to_string()))?;
        if w as u64 * h as u64 > MAX_PNG_PIXELS {
            return Err(bad(format!("{w}x{h} is more than {MAX_PNG_PIXELS} pixels")));
        }
        let img = reader()?
            .decode()
            .map_err(|e| bad(e.to_string()))?
            .to_luma8();
        let (w, h) = img.dimensions();
        let mask = img.pixels().map(|p| p.0[0] < 128).collect();
        Grid2::from_obstacles(h as usize, w as usize, mask)
    }

    /// Writes the grid as a black (obstacle) and white (free) PNG, one pixel a cell, atomically.
    ///
    /// # Errors
    /// [`GridError::Io`] or [`GridError::Image`].
    pub fn write_png(&self, path: impl AsRef<Path>) -> Result<()> {
        let img = RgbImage::from_fn(self.cols() as u32, self.rows() as u32, |x, y| {
            if self.obstacles()[y as usize * self.cols() + x as usize] {
                Rgb([0, 0, 0])
            } else {
                Rgb([255, 255, 255])
            }
        });
        write_atomic(path, &crate::canvas::encode_png(&img)?)
    }
}

/// What to draw over a field's heat map.
#[derive(Clone, Debug)]
pub struct HeatMapStyle<'a> {
    /// Pixels per cell side (at least 1).
    pub scale: u32,
    /// Obstacles to draw in black; without a grid, only infinite values are marked (grey).
    pub grid: Option<&'a Grid2>,
    /// A path drawn in red.
    pub path: &'a [Cell2],
    /// A second path (for example the optimal one) drawn in white beneath the first.
    pub reference_path: &'a [Cell2],
    /// The start, drawn as a green square.
    pub start: Option<Cell2>,
    /// The goal, drawn as a magenta square.
    pub goal: Option<Cell2>,
}

impl Default for HeatMapStyle<'_> {
    fn default() -> Self {
        Self {
            scale: 16,
            grid: None,
            path: &[],
            reference_path: &[],
            start: None,
            goal: None,
        }
    }
}

/// Obstacles.
pub const OBSTACLE_COLOR: [u8; 3] = [0, 0, 0];
/// Free cells with an infinite value (unreachable).
pub const UNREACHABLE_COLOR: [u8; 3] = [110, 110, 110];

impl Field2 {
    /// Renders the field as a heat map (viridis: dark = near, yellow = far), obstacles black,
    /// unreachable free cells grey, with optional paths, start and goal.
    ///
    /// # Errors
    /// [`GridError::Invalid`] when the grid's shape differs from the field's or `scale` is 0.
    pub fn heat_map(&self, style: &HeatMapStyle<'_>) -> Result<RgbImage> {
        let s = style.scale;
        if s == 0 {
            return Err(GridError::Invalid(
                "heat map scale must be at least 1".into(),
            ));
        }
        if let Some(g) = style.grid {
            if (g.rows(), g.cols()) != (self.rows(), self.cols()) {
                return Err(GridError::Invalid(format!(
                    "grid is {}x{} but the field is {}x{}",
                    g.rows(),
                    g.cols(),
                    self.rows(),
                    self.cols()
                )));
            }
        }
        let (lo, hi) = self.finite_range().unwrap_or((0.0, 1.0));
        let span = (hi - lo).max(f32::EPSILON);
        let (w, h) = (self.cols() as u32 * s, self.rows() as u32 * s);
        let mut img = RgbImage::from_fn(w, h, |x, y| {
            let i = (y / s) as usize * self.cols() + (x / s) as usize;
            let v = self.values()[i];
            let color = if style.grid.is_some_and(|g| g.obstacles()[i]) {
                OBSTACLE_COLOR
            } else if !v.is_finite() {
                UNREACHABLE_COLOR
            } else {
                viridis((v - lo) / span)
            };
            Rgb(color)
        });
        let width = (s as f32 / 5.0).max(1.0);
        draw_path(
            &mut img,
            style.reference_path,
            s,
            width * 1.6,
            [255, 255, 255],
        );
        draw_path(&mut img, style.path, s, width, [230, 30, 30]);
        for (cell, color) in [(style.start, [40, 220, 60]), (style.goal, [230, 40, 230])] {
            if let Some(c) = cell {
                fill_square(&mut img, c, s, color);
            }
        }
        Ok(img)
    }

    /// Writes [`Field2::heat_map`] to a PNG file atomically.
    ///
    /// # Errors
    /// As [`Field2::heat_map`], plus [`GridError::Io`] and [`GridError::Image`].
    pub fn write_png(&self, path: impl AsRef<Path>, style: &HeatMapStyle<'_>) -> Result<()> {
        write_atomic(path, &crate::canvas::encode_png(&self.heat_map(style)?)?)
    }
}

fn put(img: &mut RgbImage, x: f32, y: f32, half: f32, color: [u8; 3]) {
    let (w, h) = (img.width() as f32, img.height() as f32);
    let (x0, x1) = ((x - half).max(0.0), (x + half).min(w - 1.0));
    let (y0, y1) = ((y - half).max(0.0), (y + half).min(h - 1.0));
    for py in y0.round() as u32..=y1.round() as u32 {
        for px in x0.round() as u32..=x1.round() as u32 {
            img.put_pixel(px, py, Rgb(color));
        }
    }
}

fn draw_path(img: &mut RgbImage, path: &[Cell2], s: u32, width: f32, color: [u8; 3]) {
    let centre = |c: Cell2| {
        (
            c.col as f32 * s as f32 + s as f32 / 2.0 - 0.5,
            c.row as f32 * s as f32 + s as f32 / 2.0 - 0.5,
        )
    };
    let half = width / 2.0;
    if let [only] = path {
        let (x, y) = centre(*only);
        put(img, x, y, half, color);
    }
    for pair in path.windows(2) {
        let (a, b) = (centre(pair[0]), centre(pair[1]));
        let steps = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).max(1);
        for k in 0..=steps {
            let t = k as f32 / steps as f32;
            put(
                img,
                a.0 + (b.0 - a.0) * t,
                a.1 + (b.1 - a.1) * t,
                half,
                color,
            );
        }
    }
}

fn fill_square(img: &mut RgbImage, c: Cell2, s: u32, color: [u8; 3]) {
    let margin = s / 5;
    for y in c.row as u32 * s + margin..(c.row as u32 + 1) * s - margin {
        for x in c.col as u32 * s + margin..(c.col as u32 + 1) * s - margin {
            if x < img.width() && y < img.height() {
                img.put_pixel(x, y, Rgb(color));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_png_round_trips_and_heat_map_marks_obstacles() {
        let dir = std::env::temp_dir().join(format!("envfield-png-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut g = Grid2::new(3, 4).unwrap();
        g.set_obstacle(Cell2::new(1, 2), true).unwrap();
        let p = dir.join("g.png");
        g.write_png(&p).unwrap();
        assert_eq!(Grid2::read_png(&p).unwrap(), g);

        let mut f = Field2::new(3, 4, (0..12).map(|v| v as f32).collect()).unwrap();
        f.set(Cell2::new(1, 2), f32::INFINITY).unwrap();
        f.set(Cell2::new(2, 3), f32::INFINITY).unwrap();
        let style = HeatMapStyle {
            scale: 5,
            grid: Some(&g),
            ..Default::default()
        };
        let img = f.heat_map(&style).unwrap();
        assert_eq!(img.dimensions(), (20, 15));
        assert_eq!(img.get_pixel(12, 7).0, OBSTACLE_COLOR);
        assert_eq!(img.get_pixel(17, 12).0, UNREACHABLE_COLOR);
        f.write_png(dir.join("f.png"), &style).unwrap();
        let bad = Grid2::new(2, 2).unwrap();
        let style = HeatMapStyle {
            grid: Some(&bad),
            ..Default::default()
        };
        assert!(f.heat_map(&style).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
