//! A direct 3x3 convolution for prediction, without candle.
//!
//! The tracked convolution ([`crate::layers::Conv::forward`]) is an im2col gather and one
//! matrix multiply, so autograd sees two ops. For prediction that gather costs more than it
//! saves: it writes nine copies of the input (zeroed first), and multiplies the zero padding of
//! every tap outside the map, which at dilation 16 on a 28x28 maze is most of them. This kernel
//! reads the input in place, skips the taps outside the map, and keeps a pixel's output channels
//! in registers while it runs over the taps and input channels: one broadcast and a handful of
//! fused multiply-adds per input value. On x86-64 it is compiled again for AVX2 with FMA and
//! for AVX-512, and the widest the CPU has is picked at run time; elsewhere the portable build
//! runs (the compiler vectorises it for the baseline target). What it gained is measured in
//! `docs/notes/performance-history.md`.

/// One convolution's shape: a channels-last input (H, W, C), 3x3 taps `dilation` apart with
/// zero padding of `dilation`, and `stride`; output (Ho, Wo, Co) with Ho = (H - 1) / stride + 1.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ConvShape {
    pub(crate) h: usize,
    pub(crate) w: usize,
    pub(crate) c: usize,
    pub(crate) co: usize,
    pub(crate) dilation: usize,
    pub(crate) stride: usize,
}

impl ConvShape {
    pub(crate) fn out_hw(&self) -> (usize, usize) {
        (
            (self.h - 1) / self.stride + 1,
            (self.w - 1) / self.stride + 1,
        )
    }
}

/// `out = relu(conv(input) + bias)` for one image, or with `residual`
/// `relu(input + conv(input) + bias)` (a residual layer: stride 1 and as many output channels
/// as input channels). `weight` is the (9 * C, Co) matrix of the tracked convolution, row
/// `tap * C + ci` with taps in row-major order; `out` holds Ho * Wo * Co values.
pub(crate) fn conv3x3_relu(
    shape: ConvShape,
    input: &[f32],
    weight: &[f32],
    bias: &[f32],
    residual: bool,
    out: &mut [f32],
) {
    let (ho, wo) = shape.out_hw();
    assert_eq!(input.len(), shape.h * shape.w * shape.c, "input size");
    assert_eq!(weight.len(), 9 * shape.c * shape.co, "weight size");
    assert_eq!(bias.len(), shape.co, "bias size");
    assert_eq!(out.len(), ho * wo * shape.co, "output size");
    assert!(
        !residual || (shape.stride == 1 && shape.c == shape.co),
        "a residual layer keeps its shape"
    );
    let args = Args {
        shape,
        input,
        weight,
        bias,
        residual,
    };
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the only requirement of `conv_avx512` is a CPU with AVX-512F, checked above.
        unsafe { conv_avx512(args, out) };
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the only requirement of `conv_avx2` is a CPU with AVX2 and FMA, checked above.
        unsafe { conv_avx2(args, out) };
        return;
    }
    conv_blocks::<false, false>(args, out);
}

/// The read-only inputs of one convolution.
#[derive(Clone, Copy)]
struct Args<'a> {
    shape: ConvShape,
    input: &'a [f32],
    weight: &'a [f32],
    bias: &'a [f32],
    residual: bool,
}

/// # Safety
/// The CPU must have AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn conv_avx2(args: Args, out: &mut [f32]) {
    conv_blocks::<true, false>(args, out);
}

/// # Safety
/// The CPU must have AVX-512F (and with it AVX2 and FMA).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn conv_avx512(args: Args, out: &mut [f32]) {
    conv_blocks::<true, true>(args, out);
}

/// Splits the output channels into blocks of the widest width among 32, 16, 8, 4 and 1 that
/// divides Co, so each block's accumulators are a fixed-size array the compiler keeps in
/// vector registers. With `SPLIT` the input channels are dealt round-robin to 2 sets of
/// accumulators for 32-wide blocks and 4 for narrower ones: 8 independent multiply-add chains
/// per pixel pair either way, enough to keep both FMA units busy, which 32 vector registers
/// (AVX-512) hold and 16 (AVX2) do not. (With 2 sets, a 16-channel layer ran at half the
/// rate of a 32-channel one.)
#[inline(always)]
fn conv_blocks<const FMA: bool, const SPLIT: bool>(args: Args, out: &mut [f32]) {
    match (args.shape.co, SPLIT) {
        (co, false) if co % 32 == 0 => conv_block::<32, FMA, 1>(args, out),
        (co, true) if co % 32 == 0 => conv_block::<32, FMA, 2>(args, out),
        (co, false) if co % 16 == 0 => conv_block::<16, FMA, 1>(args, out),
        (co, true) if co % 16 == 0 => conv_block::<16, FMA, 4>(args, out),
        (co, false) if co % 8 == 0 => conv_block::<8, FMA, 1>(args, out),
        (co, true) if co % 8 == 0 => conv_block::<8, FMA, 4>(args, out),
        (co, false) if co % 4 == 0 => conv_block::<4, FMA, 1>(args, out),
        (co, true) if co % 4 == 0 => conv_block::<4, FMA, 4>(args, out),
        (_, false) => conv_block::<1, FMA, 1>(args, out),
        (_, true) => conv_block::<1, FMA, 4>(args, out),
    }
}

/// The input coordinate of each of the three taps along one axis for each output coordinate,
/// `None` where the tap falls in the zero padding.
fn axis_taps(n_out: usize, n_in: usize, dilation: usize, stride: usize) -> Vec<[Option<usize>; 3]> {
    (0..n_out)
        .map(|o| {
            [0, 1, 2].map(|k| {
                (o * stride + k * dilation)
                    .checked_sub(dilation)
                    .filter(|&i| i < n_in)
            })
        })
        .collect()
}

/// Output pixels go two at a time along a row: the pair shares every weight load, and its two
/// sets of accumulators give the multiply-adds independent chains (one set alone waits on the
/// latency of the previous multiply-add). A tap inside the map for only one pixel of the pair
/// (at the borders) runs for that pixel alone.
#[inline(always)]
fn conv_block<const B: usize, const FMA: bool, const W: usize>(args: Args, out: &mut [f32]) {
    let Args {
        shape,
        input,
        weight,
        bias,
        residual,
    } = args;
    let ConvShape { w, c, co, .. } = shape;
    let (ho, wo) = shape.out_hw();
    let taps_y = axis_taps(ho, shape.h, shape.dilation, shape.stride);
    let taps_x = axis_taps(wo, w, shape.dilation, shape.stride);
    let pixel = |iy: usize, ix: usize| &input[(iy * w + ix) * c..][..c];
    // The weights of each block of output channels side by side, (9 * C) rows of B: the
    // inner loops then walk whole `[f32; B]` rows with no bounds check.
    let packed: Vec<[f32; B]> = (0..co / B)
        .flat_map(|block| {
            weight
                .chunks_exact(co)
                .map(move |row| row[block * B..][..B].try_into().expect("B values"))
        })
        .collect();
    for (oy, ty) in taps_y.iter().enumerate() {
        let out_row = &mut out[oy * wo * co..][..wo * co];
        for ox in (0..wo).step_by(2) {
            let pair = ox + 1 < wo;
            for (block, block_rows) in packed.chunks_exact(9 * c).enumerate() {
                // Per pixel of the pair, up to 4 sets of accumulators (W in use), the first
                // starting at the bias. Separate locals, not one array: the compiler keeps
                // locals in registers, where an array indexed in a loop went through memory
                // (10x slower).
                let init: [f32; B] = bias[block * B..][..B].try_into().expect("B values");
                let zero = [0.0f32; B];
                let (mut a0, mut a1, mut a2, mut a3) = (init, zero, zero, zero);
                let (mut b0, mut b1, mut b2, mut b3) = (init, zero, zero, zero);
                for (ky, iy) in ty.iter().enumerate() {
                    let Some(iy) = *iy else { continue };
                    for kx in 0..3 {
                        let rows = &block_rows[(ky * 3 + kx) * c..][..c];
                        let second = if pair { taps_x[ox + 1][kx] } else { None };
                        match (taps_x[ox][kx], second) {
                            (Some(i0), Some(i1)) => madd_pair::<B, FMA, W>(
                                [&mut a0, &mut a1, &mut a2, &mut a3],
                                [&mut b0, &mut b1, &mut b2, &mut b3],
                                [pixel(iy, i0), pixel(iy, i1)],
                                rows,
                            ),
                            (Some(i), None) => madd_row::<B, FMA>(&mut a0, pixel(iy, i), rows),
                            (None, Some(i)) => madd_row::<B, FMA>(&mut b0, pixel(iy, i), rows),
                            (None, None) => {}
                        }
                    }
                }
                let store = |dst: &mut [f32], x: usize, sets: [[f32; B]; 4]| {
                    let dst = &mut dst[x * co + block * B..][..B];
                    let mut sum = sets[0];
                    for set in &sets[1..W] {
                        sum.iter_mut().zip(set).for_each(|(s, v)| *s += v);
                    }
                    if residual {
                        // Stride 1 and C == Co: the output pixel's input is the same pixel.
                        let skip = &pixel(oy, x)[block * B..][..B];
                        sum.iter_mut().zip(skip).for_each(|(s, v)| *s += v);
                    }
                    dst.iter_mut().zip(sum).for_each(|(o, v)| *o = v.max(0.0));
                };
                store(out_row, ox, [a0, a1, a2, a3]);
                if pair {
                    store(out_row, ox + 1, [b0, b1, b2, b3]);
                }
            }
        }
    }
}

/// `acc += a * wt`, fused where the CPU can.
#[inline(always)]
fn madd<const B: usize, const FMA: bool>(acc: &mut [f32; B], a: f32, wt: &[f32; B]) {
    for (acc, &wv) in acc.iter_mut().zip(wt) {
        *acc = if FMA {
            a.mul_add(wv, *acc)
        } else {
            *acc + a * wv
        };
    }
}

/// Two pixels' taps sharing each weight row, input channel `ci` going to accumulator set
/// `ci % W` of its pixel (W is 1, 2 or 4; the channels past the last whole group of W to the
/// first set).
#[inline(always)]
fn madd_pair<const B: usize, const FMA: bool, const W: usize>(
    [p0, p1, p2, p3]: [&mut [f32; B]; 4],
    [q0, q1, q2, q3]: [&mut [f32; B]; 4],
    [s0, s1]: [&[f32]; 2],
    rows: &[[f32; B]],
) {
    let whole = s0.len() / W * W;
    let groups = s0[..whole]
        .chunks_exact(W)
        .zip(s1[..whole].chunks_exact(W))
        .zip(rows.chunks_exact(W));
    for ((x, y), wt) in groups {
        madd::<B, FMA>(p0, x[0], &wt[0]);
        madd::<B, FMA>(q0, y[0], &wt[0]);
        if W >= 2 {
            madd::<B, FMA>(p1, x[1], &wt[1]);
            madd::<B, FMA>(q1, y[1], &wt[1]);
        }
        if W >= 4 {
            madd::<B, FMA>(p2, x[2], &wt[2]);
            madd::<B, FMA>(q2, y[2], &wt[2]);
            madd::<B, FMA>(p3, x[3], &wt[3]);
            madd::<B, FMA>(q3, y[3], &wt[3]);
        }
    }
    let rest = s0[whole..].iter().zip(&s1[whole..]).zip(&rows[whole..]);
    for ((&a, &b), wt) in rest {
        madd::<B, FMA>(p0, a, wt);
        madd::<B, FMA>(q0, b, wt);
    }
}

/// One pixel's taps: `acc += src[ci] * rows[ci]` over the input channels.
#[inline(always)]
fn madd_row<const B: usize, const FMA: bool>(acc: &mut [f32; B], src: &[f32], rows: &[[f32; B]]) {
    for (&a, wt) in src.iter().zip(rows) {
        madd::<B, FMA>(acc, a, wt);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The convolution written out from its definition (`residual`: plus the input pixel).
    fn reference(args: Args) -> Vec<f32> {
        let Args {
            shape,
            input,
            weight,
            bias,
            residual,
        } = args;
        let (ho, wo) = shape.out_hw();
        let (c, co, d) = (shape.c, shape.co, shape.dilation as isize);
        let mut out = vec![0.0; ho * wo * co];
        for oy in 0..ho {
            for ox in 0..wo {
                for o in 0..co {
                    let mut v = bias[o] as f64;
                    for t in 0..9 {
                        let iy = (oy * shape.stride) as isize + (t as isize / 3 - 1) * d;
                        let ix = (ox * shape.stride) as isize + (t as isize % 3 - 1) * d;
                        if iy < 0 || ix < 0 || iy >= shape.h as isize || ix >= shape.w as isize {
                            continue;
                        }
                        for ci in 0..c {
                            let x = input[(iy as usize * shape.w + ix as usize) * c + ci];
                            v += x as f64 * weight[(t * c + ci) * co + o] as f64;
                        }
                    }
                    if residual {
                        v += input[(oy * shape.w + ox) * c + o] as f64;
                    }
                    out[(oy * wo + ox) * co + o] = v.max(0.0) as f32;
                }
            }
        }
        out
    }

    #[test]
    fn matches_the_definition_for_every_block_width_dilation_and_stride() {
        let mut seed = 12345u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 40) as f32 / (1u64 << 24) as f32) - 0.5
        };
        // Odd and even widths (the last pixel of an odd row has no partner), every block width,
        // a dilation wider than the map, stride 2, and a single pixel; residual layers where
        // the shape allows.
        for (h, w, c, co, dilation, stride, residual) in [
            (7, 5, 3, 32, 1, 1, false),
            (9, 9, 16, 16, 2, 1, false),
            (9, 9, 16, 16, 2, 1, true),
            (6, 11, 4, 8, 4, 2, false),
            (28, 28, 5, 12, 16, 1, false),
            (28, 27, 32, 32, 8, 1, true),
            (5, 4, 2, 3, 1, 2, false),
            (4, 6, 3, 64, 8, 1, false),
            (1, 1, 1, 1, 1, 1, false),
            (1, 1, 1, 1, 1, 1, true),
        ]
        .into_iter()
        // Miri interprets every multiply: the 28x28 maps there would take hours.
        .filter(|&(h, ..)| !cfg!(miri) || h < 28)
        {
            let shape = ConvShape {
                h,
                w,
                c,
                co,
                dilation,
                stride,
            };
            let input: Vec<f32> = (0..h * w * c).map(|_| next()).collect();
            let weight: Vec<f32> = (0..9 * c * co).map(|_| next()).collect();
            let bias: Vec<f32> = (0..co).map(|_| next() * 0.1).collect();
            let (ho, wo) = shape.out_hw();
            let args = Args {
                shape,
                input: &input,
                weight: &weight,
                bias: &bias,
                residual,
            };
            let want = reference(args);
            // Every code path this CPU can run, and the one picked at run time.
            let mut paths: Vec<(&str, Vec<f32>)> = Vec::new();
            let mut run = |name, f: &dyn Fn(&mut [f32])| {
                let mut out = vec![f32::NAN; ho * wo * co];
                f(&mut out);
                paths.push((name, out));
            };
            run("dispatched", &|o| {
                conv3x3_relu(shape, &input, &weight, &bias, residual, o)
            });
            run("portable", &|o| conv_blocks::<false, false>(args, o));
            run("portable split", &|o| conv_blocks::<false, true>(args, o));
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                // SAFETY: the CPU has AVX2 and FMA.
                run("avx2", &|o| unsafe { conv_avx2(args, o) });
            }
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx512f") {
                // SAFETY: the CPU has AVX-512F.
                run("avx512", &|o| unsafe { conv_avx512(args, o) });
            }
            for (path, got) in &paths {
                for (i, (a, b)) in got.iter().zip(&want).enumerate() {
                    assert!(
                        (a - b).abs() <= 1e-5,
                        "{shape:?} {path} value {i}: {a} vs {b}"
                    );
                }
            }
        }
    }
}
