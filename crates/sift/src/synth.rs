//! Deterministic synthetic test images and the tests' random numbers: a `#[cfg(test)]` module of the library
//! for its unit tests; the integration tests (`tests/common`), the bench and the `gen_images` dev probe (`dev/`) include
//! this same file, so every test draws the same sequences.
#![allow(dead_code)]

/// A tiny 64-bit LCG (Knuth's MMIX constants); enough for test images, no dependency.
pub struct Lcg(pub u64);

impl Lcg {
    /// Next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 32) as u32
    }
    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }
    /// Uniform integer in [lo, hi).
    pub fn int(&mut self, lo: usize, hi: usize) -> usize {
        lo + (self.next_u32() as usize) % (hi - lo).max(1)
    }
}

/// Smooth random texture: a sum of random Gaussian blobs of several sizes, scaled to 0..255.
pub fn texture(w: usize, h: usize, seed: u64) -> Vec<u8> {
    let mut rng = Lcg(seed ^ 0x5eed_7e37);
    let mut acc = vec![0.0f32; w * h];
    let n_blobs = (w * h) / 300 + 8;
    for _ in 0..n_blobs {
        let cx = rng.range(-10.0, w as f32 + 10.0);
        let cy = rng.range(-10.0, h as f32 + 10.0);
        // Mostly small blobs, some large ones.
        let s = 2.0 * (rng.f32() * 3.0).exp2();
        let a = rng.range(-1.0, 1.0);
        let r = (3.0 * s).ceil() as isize;
        let inv = -0.5 / (s * s);
        let (x0, x1) = ((cx as isize - r).max(0), (cx as isize + r).min(w as isize - 1));
        let (y0, y1) = ((cy as isize - r).max(0), (cy as isize + r).min(h as isize - 1));
        for y in y0..=y1 {
            let dy = y as f32 - cy;
            for x in x0..=x1 {
                let dx = x as f32 - cx;
                acc[y as usize * w + x as usize] += a * ((dx * dx + dy * dy) * inv).exp();
            }
        }
    }
    let (lo, hi) = acc.iter().fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
    let span = (hi - lo).max(1e-6);
    acc.iter().map(|&v| ((v - lo) / span * 255.0).round() as u8).collect()
}

/// Occupancy-map look: unknown grey 205, free white 254 rooms and corridors, black walls 1-3 px thick,
/// furniture boxes.
pub fn map_like(w: usize, h: usize, seed: u64) -> Vec<u8> {
    let mut rng = Lcg(seed ^ 0x00ca_fe00);
    let mut img = vec![205u8; w * h];
    let fill = |img: &mut Vec<u8>, x0: usize, y0: usize, x1: usize, y1: usize, v: u8| {
        for y in y0.min(h)..y1.min(h) {
            for x in x0.min(w)..x1.min(w) {
                img[y * w + x] = v;
            }
        }
    };
    let outline = |img: &mut Vec<u8>, x0: usize, y0: usize, x1: usize, y1: usize, t: usize| {
        for y in y0.min(h)..y1.min(h) {
            for x in x0.min(w)..x1.min(w) {
                if x < x0 + t || x + t >= x1 || y < y0 + t || y + t >= y1 {
                    img[y * w + x] = 0;
                }
            }
        }
    };
    let margin = w.min(h) / 16 + 2;
    let mut rooms = Vec::new();
    let n_rooms = (w * h) / 40_000 + 2;
    for _ in 0..n_rooms {
        let rw = rng.int(w / 16 + 8, w / 5 + 12);
        let rh = rng.int(h / 16 + 8, h / 5 + 12);
        let x0 = rng.int(margin, w.saturating_sub(rw + margin).max(margin + 1));
        let y0 = rng.int(margin, h.saturating_sub(rh + margin).max(margin + 1));
        rooms.push((x0, y0, x0 + rw, y0 + rh, rng.int(1, 4)));
    }
    // Corridors between consecutive rooms (L-shaped), drawn as free space with walls.
    let mut corridors = Vec::new();
    for pair in rooms.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let (ax, ay) = ((a.0 + a.2) / 2, (a.1 + a.3) / 2);
        let (bx, by) = ((b.0 + b.2) / 2, (b.1 + b.3) / 2);
        let cw = rng.int(6, 14);
        corridors.push((ax.min(bx), ay, ax.max(bx) + cw, ay + cw));
        corridors.push((bx, ay.min(by), bx + cw, ay.max(by) + cw));
    }
    for &(x0, y0, x1, y1, t) in &rooms {
        outline(&mut img, x0, y0, x1, y1, t);
    }
    for &(x0, y0, x1, y1) in &corridors {
        outline(&mut img, x0.saturating_sub(2), y0.saturating_sub(2), x1 + 2, y1 + 2, 2);
    }
    for &(x0, y0, x1, y1, t) in &rooms {
        fill(&mut img, x0 + t, y0 + t, x1 - t, y1 - t, 254);
    }
    for &(x0, y0, x1, y1) in &corridors {
        fill(&mut img, x0, y0, x1, y1, 254);
    }
    // Furniture: boxes inside rooms, filled black or outlined.
    for &(x0, y0, x1, y1, t) in &rooms {
        let n = rng.int(1, 5);
        for _ in 0..n {
            let bw = rng.int(4, ((x1 - x0) / 4).max(5));
            let bh = rng.int(4, ((y1 - y0) / 4).max(5));
            let bx = rng.int(x0 + t + 2, (x1 - t).saturating_sub(bw + 2).max(x0 + t + 3));
            let by = rng.int(y0 + t + 2, (y1 - t).saturating_sub(bh + 2).max(y0 + t + 3));
            if rng.f32() < 0.5 {
                fill(&mut img, bx, by, bx + bw, by + bh, 0);
            } else {
                outline(&mut img, bx, by, bx + bw, by + bh, 1);
            }
        }
    }
    img
}

/// Bilinear sample of a grey image (`None` outside).
pub fn bilinear(img: &[f32], w: usize, h: usize, x: f32, y: f32) -> Option<f32> {
    if !(x >= 0.0 && y >= 0.0 && x <= (w - 1) as f32 && y <= (h - 1) as f32) {
        return None;
    }
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let top = img[y0 * w + x0] * (1.0 - fx) + img[y0 * w + x1] * fx;
    let bot = img[y1 * w + x0] * (1.0 - fx) + img[y1 * w + x1] * fx;
    Some(top * (1.0 - fy) + bot * fy)
}

/// Warps `img` into a `dw x dh` image: output pixel p samples input at `inv(p)` (bilinear, `fill` outside).
pub fn warp(
    img: &[f32],
    w: usize,
    h: usize,
    dw: usize,
    dh: usize,
    fill: f32,
    inv: impl Fn(f32, f32) -> (f32, f32),
) -> Vec<f32> {
    let mut out = vec![fill; dw * dh];
    for y in 0..dh {
        for x in 0..dw {
            let (sx, sy) = inv(x as f32, y as f32);
            if let Some(v) = bilinear(img, w, h, sx, sy) {
                out[y * dw + x] = v;
            }
        }
    }
    out
}

/// Halves an image by averaging 2x2 blocks (pixel centres map as x_small = (x_big - 0.5) / 2).
pub fn halve(img: &[f32], w: usize, h: usize) -> Vec<f32> {
    let (dw, dh) = (w / 2, h / 2);
    let mut out = vec![0.0; dw * dh];
    for y in 0..dh {
        for x in 0..dw {
            let i = 2 * y * w + 2 * x;
            out[y * dw + x] = 0.25 * (img[i] + img[i + 1] + img[i + w] + img[i + w + 1]);
        }
    }
    out
}
