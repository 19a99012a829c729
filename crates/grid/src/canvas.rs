//! [`Canvas`]: the one picture kit of the workspace. Squares, dots, segments, discs and crosses
//! on an RGB image in pixel coordinates (clipped at the edges), written as PNG or as a looping
//! GIF through the atomic writer.

use crate::io::write_atomic;
use crate::Result;
use image::{ImageEncoder, Rgb, RgbImage};
use std::path::Path;

/// An RGB picture to draw on. Every drawing call clips at the edges, so a shape partly or
/// wholly outside draws what is inside and nothing else.
#[derive(Clone, Debug, PartialEq)]
pub struct Canvas {
    img: RgbImage,
}

impl Canvas {
    /// A `width` x `height` canvas filled with `background`.
    pub fn new(width: u32, height: u32, background: [u8; 3]) -> Self {
        Self {
            img: RgbImage::from_pixel(width, height, Rgb(background)),
        }
    }

    /// A canvas holding `img`.
    pub fn from_image(img: RgbImage) -> Self {
        Self { img }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.img.width()
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.img.height()
    }

    /// The picture.
    pub fn image(&self) -> &RgbImage {
        &self.img
    }

    /// The colour at pixel (x, y), `None` outside.
    pub fn get(&self, x: u32, y: u32) -> Option<[u8; 3]> {
        (x < self.width() && y < self.height()).then(|| self.img.get_pixel(x, y).0)
    }

    /// One pixel, when (x, y) is on the canvas.
    pub fn put(&mut self, x: i64, y: i64, colour: [u8; 3]) {
        if x >= 0 && y >= 0 && x < self.width() as i64 && y < self.height() as i64 {
            self.img.put_pixel(x as u32, y as u32, Rgb(colour));
        }
    }

    /// A `width` x `height` rectangle with its top-left corner at pixel (x, y).
    pub fn fill(&mut self, x: i64, y: i64, width: u32, height: u32, colour: [u8; 3]) {
        for dy in 0..height as i64 {
            for dx in 0..width as i64 {
                self.put(x + dx, y + dy, colour);
            }
        }
    }

    /// A square of half-side `half` pixels centred on the pixel under (x, y).
    pub fn dot(&mut self, x: f32, y: f32, half: i64, colour: [u8; 3]) {
        let (cx, cy) = (x as i64, y as i64);
        for dy in -half..=half {
            for dx in -half..=half {
                self.put(cx + dx, cy + dy, colour);
            }
        }
    }

    /// A segment from `a` to `b` (pixels), one [`Canvas::dot`] of half-side `half` every
    /// pixel of its length.
    pub fn segment(&mut self, a: (f32, f32), b: (f32, f32), half: i64, colour: [u8; 3]) {
        let n = (b.0 - a.0).hypot(b.1 - a.1).ceil().max(1.0) as usize;
        for k in 0..=n {
            let t = k as f32 / n as f32;
            self.dot(a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1), half, colour);
        }
    }

    /// A thin segment from `a` to `b`: at every pixel of its longer axis, the pixel under the
    /// point and its right and lower neighbours.
    pub fn line(&mut self, a: (f32, f32), b: (f32, f32), colour: [u8; 3]) {
        let n = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).max(1);
        for k in 0..=n {
            let s = k as f32 / n as f32;
            let (x, y) = (a.0 + s * (b.0 - a.0), a.1 + s * (b.1 - a.1));
            for (dx, dy) in [(0, 0), (1, 0), (0, 1)] {
                self.put(x as i64 + dx, y as i64 + dy, colour);
            }
        }
    }

    /// A disc of `radius` pixels centred on (x, y), filled with `colour` and ringed 1.5 pixels
    /// wide with `edge`.
    pub fn disc(&mut self, x: f32, y: f32, radius: f32, colour: [u8; 3], edge: [u8; 3]) {
        let r = radius as i64;
        for dy in -r..=r {
            for dx in -r..=r {
                let d = ((dx * dx + dy * dy) as f32).sqrt();
                if d <= radius {
                    let c = if d > radius - 1.5 { edge } else { colour };
                    self.put(x as i64 + dx, y as i64 + dy, c);
                }
            }
        }
    }

    /// A cross of two diagonal strokes, each two pixels thick, reaching `half` pixels from
    /// (x, y).
    pub fn cross(&mut self, x: f32, y: f32, half: i64, colour: [u8; 3]) {
        for d in -half..=half {
            for w in 0..2 {
                self.put(x as i64 + d, y as i64 + d + w, colour);
                self.put(x as i64 + d, y as i64 - d + w, colour);
            }
        }
    }

    /// The part of the canvas from (x, y), `width` x `height`, clipped to the canvas.
    pub fn crop(&self, x: u32, y: u32, width: u32, height: u32) -> Canvas {
        Canvas {
            img: image::imageops::crop_imm(&self.img, x, y, width, height).to_image(),
        }
    }

    /// The picture encoded as PNG.
    ///
    /// # Errors
    /// [`GridError`](crate::GridError) from the encoder (it does not fail on a canvas).
    pub fn png_bytes(&self) -> Result<Vec<u8>> {
        encode_png(&self.img)
    }

    /// Writes the picture as PNG, atomically.
    ///
    /// # Errors
    /// I/O errors naming the file.
    pub fn write_png(&self, path: impl AsRef<Path>) -> Result<()> {
        write_atomic(path, &self.png_bytes()?)
    }

    /// Writes `frames` as an animated GIF that loops, `delay_ms` per frame, atomically.
    ///
    /// # Errors
    /// I/O errors naming the file; encoder errors.
    pub fn write_gif(frames: &[Canvas], delay_ms: u32, path: impl AsRef<Path>) -> Result<()> {
        use image::codecs::gif::{GifEncoder, Repeat};
        let mut bytes = Vec::new();
        {
            let mut encoder = GifEncoder::new_with_speed(&mut bytes, 20);
            encoder.set_repeat(Repeat::Infinite)?;
            let delay = image::Delay::from_numer_denom_ms(delay_ms, 1);
            encoder.encode_frames(frames.iter().map(|f| {
                let rgba = image::DynamicImage::ImageRgb8(f.img.clone()).to_rgba8();
                image::Frame::from_parts(rgba, 0, 0, delay)
            }))?;
        }
        write_atomic(path, &bytes)
    }
}

/// `img` encoded as PNG: the one PNG encoder of the picture kit.
pub(crate) fn encode_png(img: &image::RgbImage) -> Result<Vec<u8>> {
    let mut buf = Vec::new();
    image::codecs::png::PngEncoder::new(&mut buf).write_image(
        img.as_raw(),
        img.width(),
        img.height(),
        image::ExtendedColorType::Rgb8,
    )?;
    Ok(buf)
}

/// Linear between evenly spaced `stops`, `t` in `[0, 1]` (clamped).
fn ramp(stops: &[[f32; 3]], t: f32) -> [u8; 3] {
    let x = t.clamp(0.0, 1.0) * (stops.len() - 1) as f32;
    let i = (x.floor() as usize).min(stops.len() - 2);
    let f = x - i as f32;
    [0, 1, 2].map(|k| (stops[i][k] * (1.0 - f) + stops[i + 1][k] * f).round() as u8)
}

/// Viridis, sampled at 6 points: dark purple at 0, yellow at 1 (the heat maps' distances).
pub fn viridis(t: f32) -> [u8; 3] {
    ramp(
        &[
            [68.0, 1.0, 84.0],
            [65.0, 68.0, 135.0],
            [42.0, 120.0, 142.0],
            [34.0, 168.0, 132.0],
            [122.0, 209.0, 81.0],
            [253.0, 231.0, 37.0],
        ],
        t,
    )
}

/// A height from 0 (low) to 1 (high) as dark blue through teal and green to yellow (plan
/// views and point clouds of 3D regions).
pub fn height_colour(t: f32) -> [u8; 3] {
    ramp(
        &[
            [40.0, 50.0, 140.0],
            [30.0, 140.0, 150.0],
            [110.0, 190.0, 80.0],
            [250.0, 225.0, 60.0],
        ],
        t,
    )
}

/// `colour` mixed with white: `keep` of the colour, the rest white.
pub fn tint(colour: [u8; 3], keep: f32) -> [u8; 3] {
    colour.map(|v| (v as f32 * keep + 255.0 * (1.0 - keep)) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_clip_at_the_edges_and_round_trip_through_png() {
        let mut c = Canvas::new(10, 8, [0, 0, 0]);
        c.dot(0.0, 0.0, 2, [255, 0, 0]);
        c.segment((-5.0, 4.0), (20.0, 4.0), 0, [0, 255, 0]);
        c.disc(9.0, 7.0, 2.0, [0, 0, 255], [9, 9, 9]);
        assert_eq!(c.get(0, 0), Some([255, 0, 0]));
        assert_eq!(c.get(2, 2), Some([255, 0, 0]));
        assert_eq!(c.get(3, 3), Some([0, 0, 0]));
        assert!((0..10).all(|x| c.get(x, 4) == Some([0, 255, 0])));
        assert_eq!(c.get(9, 7), Some([0, 0, 255]));
        assert_eq!(c.get(10, 0), None);
        let back = image::load_from_memory(&c.png_bytes().unwrap())
            .unwrap()
            .to_rgb8();
        assert_eq!(&back, c.image());
        assert_eq!(c.crop(8, 6, 5, 5).width(), 2);
    }
}
