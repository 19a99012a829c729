//! VIN's forward and backward written by hand over plain buffers.
//!
//! At VIN's sizes (2 input channels, 10 Q channels, 8x8 to 28x28 maps) every candle op costs
//! more in dispatch and allocation than in arithmetic, and the value-iteration loop is 2(K + 1)
//! of them. Here one map's whole pass is a few loops over preallocated planes:
//!
//! - `h` (3x3, 2 -> hidden, with bias) and `r` (1x1, hidden -> 1) have no activation between
//!   them, so the reward map is one 3x3 convolution of the input with the weights folded
//!   (`E = sum_c r_c h_c`); the backward unfolds the gradient the same way, exactly.
//! - The reward's half of the Q convolution is the same at every iteration and is done once.
//! - Back through `v = max_a q`, the gradient reaches one Q channel per cell, so the backward
//!   of each iteration is 9 multiply-adds per cell, not 9 x 10.
//!
//! Planes are padded by one cell of zeros on every side (the 3x3 convolutions' zero padding),
//! so a tap is an offset. Weight layouts are those of the network's files: a 3x3 convolution
//! is `(9 * cin, cout)` with row `tap * cin + channel`, tap `(dy + 1) * 3 + (dx + 1)`.

/// The network's weights as plain vectors, in the file's order and layout.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Weights {
    /// `h.weight` (18, hidden): input channel 0 is the obstacle map, 1 the goal's reward.
    pub(crate) h_w: Vec<f32>,
    /// `h.bias` (hidden).
    pub(crate) h_b: Vec<f32>,
    /// `r.weight` (hidden, 1).
    pub(crate) r_w: Vec<f32>,
    /// `r.bias` (1).
    pub(crate) r_b: Vec<f32>,
    /// `q.weight` (18, q): input channel 0 is the reward, 1 the value.
    pub(crate) q_w: Vec<f32>,
    /// `q.bias` (q).
    pub(crate) q_b: Vec<f32>,
    /// `policy.weight` (q, 8).
    pub(crate) p_w: Vec<f32>,
    /// `policy.bias` (8).
    pub(crate) p_b: Vec<f32>,
}

/// Actions (the eight moves).
pub(crate) const ACTIONS: usize = 8;

impl Weights {
    /// The parts in the file's order (the order of the network's `ParamStore`).
    pub(crate) fn parts(&self) -> [&Vec<f32>; 8] {
        [
            &self.h_w, &self.h_b, &self.r_w, &self.r_b, &self.q_w, &self.q_b, &self.p_w, &self.p_b,
        ]
    }

    /// The parts in the file's order, mutable.
    pub(crate) fn parts_mut(&mut self) -> [&mut Vec<f32>; 8] {
        [
            &mut self.h_w,
            &mut self.h_b,
            &mut self.r_w,
            &mut self.r_b,
            &mut self.q_w,
            &mut self.q_b,
            &mut self.p_w,
            &mut self.p_b,
        ]
    }

    /// Builds the weights from the parts in file order (checked by the caller's shapes).
    pub(crate) fn from_parts(mut parts: Vec<Vec<f32>>) -> Self {
        debug_assert_eq!(parts.len(), 8);
        let mut next = || parts.remove(0);
        Self {
            h_w: next(),
            h_b: next(),
            r_w: next(),
            r_b: next(),
            q_w: next(),
            q_b: next(),
            p_w: next(),
            p_b: next(),
        }
    }

    /// All zeros, shaped like `self`.
    pub(crate) fn zeros_like(&self) -> Self {
        Self::from_parts(self.parts().iter().map(|p| vec![0.0; p.len()]).collect())
    }

    /// `self += other`.
    pub(crate) fn add(&mut self, other: &Self) {
        for (a, b) in self.parts_mut().into_iter().zip(other.parts()) {
            a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
        }
    }

    fn hidden(&self) -> usize {
        self.h_b.len()
    }

    fn q_channels(&self) -> usize {
        self.q_b.len()
    }
}

/// One map: its obstacles (row-major), size and the goal's flat index.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MapInput<'a> {
    pub(crate) obstacles: &'a [bool],
    pub(crate) rows: usize,
    pub(crate) cols: usize,
    pub(crate) goal: usize,
}

/// The goal's reward in the input (VIN's).
const GOAL_REWARD: f32 = 10.0;

/// The taps of a 3x3 convolution, in weight order.
fn taps() -> impl Iterator<Item = (usize, isize, isize)> {
    (0..9).map(|t| (t, t as isize / 3 - 1, t as isize % 3 - 1))
}

/// Planes of `rows x cols` padded by one zero cell on each side.
#[derive(Clone, Copy, Debug)]
struct Shape {
    rows: usize,
    cols: usize,
}

impl Shape {
    fn stride(self) -> usize {
        self.cols + 2
    }
    fn padded_len(self) -> usize {
        (self.rows + 2) * self.stride()
    }
    fn len(self) -> usize {
        self.rows * self.cols
    }
    /// The padded index of interior row `i` shifted by tap `(dy, dx)`, at column `dx + 1`.
    fn row_start(self, i: usize, dy: isize, dx: isize) -> usize {
        ((i as isize + 1 + dy) as usize) * self.stride() + (1 + dx) as usize
    }
    /// Interior flat index -> padded index.
    fn pad(self, p: usize) -> usize {
        (p / self.cols + 1) * self.stride() + p % self.cols + 1
    }
}

/// `dst += w * src shifted by the tap` (dst interior, src padded): a convolution's one term.
fn shifted_axpy(shape: Shape, dst: &mut [f32], src: &[f32], dy: isize, dx: isize, w: f32) {
    let c = shape.cols;
    for i in 0..shape.rows {
        let s = shape.row_start(i, dy, dx);
        dst[i * c..(i + 1) * c]
            .iter_mut()
            .zip(&src[s..s + c])
            .for_each(|(d, x)| *d += w * x);
    }
}

/// `dst shifted by the tap += w * src` (dst padded, src interior): the transposed term.
fn shifted_axpy_t(shape: Shape, dst: &mut [f32], src: &[f32], dy: isize, dx: isize, w: f32) {
    let c = shape.cols;
    for i in 0..shape.rows {
        let s = shape.row_start(i, dy, dx);
        dst[s..s + c]
            .iter_mut()
            .zip(&src[i * c..(i + 1) * c])
            .for_each(|(d, x)| *d += w * x);
    }
}

/// `sum a * (b shifted by the tap)` (a interior, b padded), in eight lanes so it vectorises.
fn shifted_dot(shape: Shape, a: &[f32], b: &[f32], dy: isize, dx: isize) -> f32 {
    let c = shape.cols;
    let mut lanes = [0f32; 8];
    let mut tail = 0f32;
    for i in 0..shape.rows {
        let s = shape.row_start(i, dy, dx);
        let (ra, rb) = (&a[i * c..(i + 1) * c], &b[s..s + c]);
        let mut ca = ra.chunks_exact(8);
        let mut cb = rb.chunks_exact(8);
        for (x, y) in (&mut ca).zip(&mut cb) {
            for l in 0..8 {
                lanes[l] += x[l] * y[l];
            }
        }
        tail += ca
            .remainder()
            .iter()
            .zip(cb.remainder())
            .map(|(x, y)| x * y)
            .sum::<f32>();
    }
    lanes.iter().sum::<f32>() + tail
}

/// One map's forward pass, with what the backward needs when `keep` was set.
#[derive(Debug)]
pub(crate) struct Forward {
    shape: Shape,
    /// The two input planes, padded.
    input: [Vec<f32>; 2],
    /// The reward map, padded.
    reward: Vec<f32>,
    /// The final Q maps, `q_channels` interior planes.
    pub(crate) q: Vec<f32>,
    /// v^1 .. v^K, padded (kept for the backward).
    values: Vec<Vec<f32>>,
    /// argmax_a q^(k-1) for k = 1..K, per interior cell (kept for the backward).
    argmax: Vec<Vec<u8>>,
}

/// The reward map's folded weights `E` (2 x 9) and constant `r0`.
fn folded_reward(wt: &Weights) -> ([[f32; 9]; 2], f32) {
    let hidden = wt.hidden();
    let mut e = [[0f32; 9]; 2];
    for (t, _, _) in taps() {
        for (ch, row) in e.iter_mut().enumerate() {
            let w = &wt.h_w[(t * 2 + ch) * hidden..(t * 2 + ch + 1) * hidden];
            row[t] = w.iter().zip(&wt.r_w).map(|(a, b)| a * b).sum();
        }
    }
    let r0 = wt.r_b[0] + wt.h_b.iter().zip(&wt.r_w).map(|(a, b)| a * b).sum::<f32>();
    (e, r0)
}

/// VIN's forward on one map with `iterations` steps of value iteration: the Q maps after the
/// last step (and, with `keep`, the values and argmaxes the backward needs).
pub(crate) fn forward(wt: &Weights, map: MapInput, iterations: usize, keep: bool) -> Forward {
    let shape = Shape {
        rows: map.rows,
        cols: map.cols,
    };
    let (n, qc) = (shape.len(), wt.q_channels());
    let mut input = [
        vec![0f32; shape.padded_len()],
        vec![0f32; shape.padded_len()],
    ];
    for (p, &o) in map.obstacles.iter().enumerate() {
        input[0][shape.pad(p)] = f32::from(u8::from(o));
    }
    input[1][shape.pad(map.goal)] = GOAL_REWARD;

    let (e, r0) = folded_reward(wt);
    let mut r = vec![r0; n];
    for (t, dy, dx) in taps() {
        for ch in 0..2 {
            shifted_axpy(shape, &mut r, &input[ch], dy, dx, e[ch][t]);
        }
    }
    let mut reward = vec![0f32; shape.padded_len()];
    for (p, &x) in r.iter().enumerate() {
        reward[shape.pad(p)] = x;
    }

    // The reward's half of the Q convolution, and the bias: the same at every iteration.
    let mut base = vec![0f32; qc * n];
    for (a, plane) in base.chunks_exact_mut(n).enumerate() {
        plane.fill(wt.q_b[a]);
        for (t, dy, dx) in taps() {
            shifted_axpy(shape, plane, &reward, dy, dx, wt.q_w[(t * 2) * qc + a]);
        }
    }
    let mut q = base.clone();
    let mut values = Vec::new();
    let mut argmax = Vec::new();
    let mut v = vec![0f32; shape.padded_len()];
    let mut best = vec![0u8; n];
    for _ in 0..iterations {
        for p in 0..n {
            let (mut m, mut k) = (q[p], 0u8);
            for a in 1..qc {
                if q[a * n + p] > m {
                    (m, k) = (q[a * n + p], a as u8);
                }
            }
            v[shape.pad(p)] = m;
            best[p] = k;
        }
        q.copy_from_slice(&base);
        for (a, plane) in q.chunks_exact_mut(n).enumerate() {
            for (t, dy, dx) in taps() {
                shifted_axpy(shape, plane, &v, dy, dx, wt.q_w[(t * 2 + 1) * qc + a]);
            }
        }
        if keep {
            values.push(v.clone());
            argmax.push(best.clone());
        }
    }
    Forward {
        shape,
        input,
        reward,
        q,
        values,
        argmax,
    }
}

/// The action logits at interior cell `p` from the final Q maps.
pub(crate) fn logits(wt: &Weights, q: &[f32], cells: usize, p: usize) -> [f32; ACTIONS] {
    let mut z = [0f32; ACTIONS];
    z.copy_from_slice(&wt.p_b);
    for a in 0..wt.q_channels() {
        let qa = q[a * cells + p];
        for (o, zo) in z.iter_mut().enumerate() {
            *zo += qa * wt.p_w[a * ACTIONS + o];
        }
    }
    z
}

/// The summed cross-entropy of `states` (interior cell, action label) under a forward pass
/// kept for the backward, and its gradient added to `grad` (summed, not averaged).
pub(crate) fn backward(
    wt: &Weights,
    fwd: &Forward,
    states: &[(usize, u8)],
    grad: &mut Weights,
) -> f32 {
    let shape = fwd.shape;
    let (n, qc) = (shape.len(), wt.q_channels());
    let mut loss = 0f32;
    // The policy head and dL/dq^K (dense over channels, at the states only).
    let mut gq = vec![0f32; qc * n];
    for &(p, label) in states {
        let z = logits(wt, &fwd.q, n, p);
        let m = z.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let sum: f32 = z.iter().map(|x| (x - m).exp()).sum();
        loss += m + sum.ln() - z[label as usize];
        for (o, &zo) in z.iter().enumerate() {
            let dz = (zo - m).exp() / sum - f32::from(u8::from(o == label as usize));
            grad.p_b[o] += dz;
            for a in 0..qc {
                grad.p_w[a * ACTIONS + o] += fwd.q[a * n + p] * dz;
                gq[a * n + p] += wt.p_w[a * ACTIONS + o] * dz;
            }
        }
    }
    let mut g_base = gq.clone();
    let iterations = fwd.values.len();
    if iterations > 0 {
        // q^K = base + conv(v^K): dense over channels once.
        let v = &fwd.values[iterations - 1];
        let mut gv = vec![0f32; shape.padded_len()];
        for a in 0..qc {
            let plane = &gq[a * n..(a + 1) * n];
            for (t, dy, dx) in taps() {
                let row = (t * 2 + 1) * qc + a;
                grad.q_w[row] += shifted_dot(shape, plane, v, dy, dx);
                shifted_axpy_t(shape, &mut gv, plane, dy, dx, wt.q_w[row]);
            }
        }
        // Below it, q^(k-1) gets v^k's gradient on its argmax channel only.
        let mut g = vec![0f32; n];
        for k in (0..iterations).rev() {
            let best = &fwd.argmax[k];
            for p in 0..n {
                g[p] = gv[shape.pad(p)];
                g_base[best[p] as usize * n + p] += g[p];
            }
            if k == 0 {
                break; // q^0 = base: v^0 is zero and has no weights to reach.
            }
            let v = &fwd.values[k - 1];
            gv.fill(0.0);
            for (t, dy, dx) in taps() {
                let c = shape.cols;
                let mut acc = vec![0f32; qc];
                for i in 0..shape.rows {
                    let s = shape.row_start(i, dy, dx);
                    for j in 0..c {
                        let p = i * c + j;
                        let a = best[p] as usize;
                        acc[a] += g[p] * v[s + j];
                        gv[s + j] += wt.q_w[(t * 2 + 1) * qc + a] * g[p];
                    }
                }
                for (a, x) in acc.iter().enumerate() {
                    grad.q_w[(t * 2 + 1) * qc + a] += x;
                }
            }
        }
    }
    // base = bias + conv(reward): back to the reward map.
    let mut gr = vec![0f32; shape.padded_len()];
    for a in 0..qc {
        let plane = &g_base[a * n..(a + 1) * n];
        grad.q_b[a] += plane.iter().sum::<f32>();
        for (t, dy, dx) in taps() {
            let row = (t * 2) * qc + a;
            grad.q_w[row] += shifted_dot(shape, plane, &fwd.reward, dy, dx);
            shifted_axpy_t(shape, &mut gr, plane, dy, dx, wt.q_w[row]);
        }
    }
    let gr: Vec<f32> = (0..n).map(|p| gr[shape.pad(p)]).collect();
    // The folded reward weights, unfolded into h and r.
    let g_r0: f32 = gr.iter().sum();
    let hidden = wt.hidden();
    let mut ge = [[0f32; 9]; 2];
    for (t, dy, dx) in taps() {
        for (ch, row) in ge.iter_mut().enumerate() {
            row[t] = shifted_dot(shape, &gr, &fwd.input[ch], dy, dx);
        }
    }
    grad.r_b[0] += g_r0;
    for c in 0..hidden {
        let mut gw = wt.h_b[c] * g_r0;
        for (t, _, _) in taps() {
            for (ch, row) in ge.iter().enumerate() {
                let i = (t * 2 + ch) * hidden + c;
                gw += wt.h_w[i] * row[t];
                grad.h_w[i] += wt.r_w[c] * row[t];
            }
        }
        grad.r_w[c] += gw;
        grad.h_b[c] += wt.r_w[c] * g_r0;
    }
    loss
}

#[cfg(test)]
mod tests;
