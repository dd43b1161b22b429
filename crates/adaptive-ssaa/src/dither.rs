//! Sample choice inside the sampling window (§4.3.2): the `k` samples of a pixel are the
//! cells holding indices `0..k` of an ordered-dither index matrix (Bayer 1973).

/// The index matrices of Figure 4.7 (row-major, `m = 2, 3, 4`).
const FIGURE_4_7: [&[u32]; 3] = [
    &[0, 2, 3, 1],
    &[2, 6, 3, 5, 0, 8, 1, 7, 4],
    &[1, 8, 2, 10, 12, 4, 14, 6, 3, 11, 0, 9, 15, 7, 13, 5],
];

/// The index matrix of an `m × m` window, row-major: cell `(x, y)` holds `matrix[y·m + x]`, the
/// rank of that sample. For `m = 2, 3, 4` the matrices of Figure 4.7 as printed; for other
/// powers of two Bayer's recursive matrix ([`bayer_matrix`]); otherwise a greedy
/// farthest-point order on the torus (each next sample in the cell farthest from all earlier
/// ones, wrapping around the window's edges as the windows tile the image; ties go to the
/// cell farthest from the previous sample, then to the first in row-major order).
pub fn dither_matrix(m: u32) -> Vec<u32> {
    match m {
        2..=4 => FIGURE_4_7[m as usize - 2].to_vec(),
        _ if m.is_power_of_two() => bayer_matrix(m),
        _ => farthest_point_matrix(m),
    }
}

/// Bayer's ordered-dither matrix for a power-of-two `m`: `M₁ = (0)` and
/// `M₂ₛ = [[4Mₛ, 4Mₛ + 2], [4Mₛ + 3, 4Mₛ + 1]]`.
pub fn bayer_matrix(m: u32) -> Vec<u32> {
    assert!(
        m.is_power_of_two(),
        "Bayer matrices have power-of-two sides"
    );
    let mut s = 1u32;
    let mut cur = vec![0u32];
    while s < m {
        let t = 2 * s;
        let mut next = vec![0; (t * t) as usize];
        for y in 0..t {
            for x in 0..t {
                let quadrant = [0, 2, 3, 1][((y / s) * 2 + x / s) as usize];
                next[(y * t + x) as usize] = 4 * cur[((y % s) * s + x % s) as usize] + quadrant;
            }
        }
        cur = next;
        s = t;
    }
    cur
}

fn torus_distance2(a: [u32; 2], b: [u32; 2], m: u32) -> u32 {
    let d = |p: u32, q: u32| {
        let d = p.abs_diff(q);
        d.min(m - d)
    };
    d(a[0], b[0]).pow(2) + d(a[1], b[1]).pow(2)
}

fn farthest_point_matrix(m: u32) -> Vec<u32> {
    let n = (m * m) as usize;
    let cell = |i: usize| [i as u32 % m, i as u32 / m];
    let mut matrix = vec![u32::MAX; n];
    let centre = (m / 2 * m + m / 2) as usize;
    matrix[centre] = 0;
    let mut placed = vec![cell(centre)];
    for rank in 1..n as u32 {
        let previous = placed[placed.len() - 1];
        let best = (0..n)
            .filter(|&i| matrix[i] == u32::MAX)
            .max_by_key(|&i| {
                let nearest = placed
                    .iter()
                    .map(|&p| torus_distance2(p, cell(i), m))
                    .min()
                    .unwrap_or(0);
                (
                    nearest,
                    torus_distance2(previous, cell(i), m),
                    std::cmp::Reverse(i),
                )
            })
            .unwrap_or(0);
        matrix[best] = rank;
        placed.push(cell(best));
    }
    matrix
}

/// The window cells `(x, y)` in sample order: entry `i` is where [`dither_matrix`] holds `i`.
pub fn dither_order(m: u32) -> Vec<[u32; 2]> {
    let matrix = dither_matrix(m);
    let mut order = vec![[0, 0]; matrix.len()];
    for (cell, &rank) in matrix.iter().enumerate() {
        order[rank as usize] = [cell as u32 % m, cell as u32 / m];
    }
    order
}

/// The spread of an order: for every prefix of `k = 2..=n` samples, the smallest distance
/// between two of them on the torus (windows tile the image), in samples.
pub fn prefix_spread(order: &[[u32; 2]], m: u32) -> Vec<f32> {
    (2..=order.len())
        .map(|k| {
            let prefix = &order[..k];
            let mut best = u32::MAX;
            for (i, &a) in prefix.iter().enumerate() {
                for &b in &prefix[i + 1..] {
                    best = best.min(torus_distance2(a, b, m));
                }
            }
            (best as f32).sqrt()
        })
        .collect()
}
