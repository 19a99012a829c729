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
//! runs (the compiler vectorises it for the baseline target).
//!
//! Measured on this project's 2-core machine (AVX-512) in `maze_nav` on VIN's 28x28 test set,
//! one thread, 11-convolution default encoder: 4.1 ms per path with the im2col gather and
//! candle's matrix multiply, 2.4 ms with this kernel built for AVX2, 1.5-1.8 ms for AVX-512
//! (another training sharing the cores in every case).

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
/// vector registers.
#[inline(always)]
fn conv_blocks<const FMA: bool, const SPLIT: bool>(args: Args, out: &mut [f32]) {
    match args.shape.co {
        co if co % 32 == 0 => conv_block::<32, FMA, SPLIT>(args, out),
        co if co % 16 == 0 => conv_block::<16, FMA, SPLIT>(args, out),
        co if co % 8 == 0 => conv_block::<8, FMA, SPLIT>(args, out),
        co if co % 4 == 0 => conv_block::<4, FMA, SPLIT>(args, out),
        _ => conv_block::<1, FMA, SPLIT>(args, out),
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
fn conv_block<const B: usize, const FMA: bool, const SPLIT: bool>(args: Args, out: &mut [f32]) {
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
                let init: [f32; B] = bias[block * B..][..B].try_into().expect("B values");
                let (mut acc0, mut acc1) = (init, init);
                let (mut odd0, mut odd1) = ([0.0; B], [0.0; B]);
                for (ky, iy) in ty.iter().enumerate() {
                    let Some(iy) = *iy else { continue };
                    for kx in 0..3 {
                        let rows = &block_rows[(ky * 3 + kx) * c..][..c];
                        let second = if pair { taps_x[ox + 1][kx] } else { None };
                        match (taps_x[ox][kx], second) {
                            (Some(i0), Some(i1)) => madd_pair::<B, FMA, SPLIT>(
                                [&mut acc0, &mut acc1],
                                [&mut odd0, &mut odd1],
                                [pixel(iy, i0), pixel(iy, i1)],
                                rows,
                            ),
                            (Some(i), None) => madd_row::<B, FMA>(&mut acc0, pixel(iy, i), rows),
                            (None, Some(i)) => madd_row::<B, FMA>(&mut acc1, pixel(iy, i), rows),
                            (None, None) => {}
                        }
                    }
                }
                let store = |dst: &mut [f32], x: usize, acc: [f32; B], odd: [f32; B]| {
                    let dst = &mut dst[x * co + block * B..][..B];
                    if residual {
                        // Stride 1 and C == Co: the output pixel's input is the same pixel.
                        let skip = &pixel(oy, x)[block * B..][..B];
                        for (((o, v), u), s) in dst.iter_mut().zip(acc).zip(odd).zip(skip) {
                            *o = (v + u + s).max(0.0);
                        }
                    } else {
                        for ((o, v), u) in dst.iter_mut().zip(acc).zip(odd) {
                            *o = (v + u).max(0.0);
                        }
                    }
                };
                store(out_row, ox, acc0, odd0);
                if pair {
                    store(out_row, ox + 1, acc1, odd1);
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

/// Two pixels' taps sharing each weight row. With `SPLIT`, odd input channels go to a second
/// set of accumulators (`odd`): four independent chains instead of two, which 32 vector
/// registers (AVX-512) hold and 16 (AVX2) do not.
#[inline(always)]
fn madd_pair<const B: usize, const FMA: bool, const SPLIT: bool>(
    [acc0, acc1]: [&mut [f32; B]; 2],
    [odd0, odd1]: [&mut [f32; B]; 2],
    [s0, s1]: [&[f32]; 2],
    rows: &[[f32; B]],
) {
    let mut done = 0;
    if SPLIT {
        let (p0, p1) = (s0.chunks_exact(2), s1.chunks_exact(2));
        done = 2 * p0.len();
        for ((a0, a1), wt) in p0.zip(p1).zip(rows.chunks_exact(2)) {
            madd::<B, FMA>(acc0, a0[0], &wt[0]);
            madd::<B, FMA>(acc1, a1[0], &wt[0]);
            madd::<B, FMA>(odd0, a0[1], &wt[1]);
            madd::<B, FMA>(odd1, a1[1], &wt[1]);
        }
    }
    for ((&a0, &a1), wt) in s0[done..].iter().zip(&s1[done..]).zip(&rows[done..]) {
        madd::<B, FMA>(acc0, a0, wt);
        madd::<B, FMA>(acc1, a1, wt);
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
        ] {
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
