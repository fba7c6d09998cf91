//! Vector kernels, in one place: the sequential ones of the small dense loops on Γ_C and the
//! blocked parallel ones of the Krylov solver. Two dot products with two summation orders are
//! two algorithms, so they have two names ([`dot`], [`par_dot`]): each keeps its results to the
//! bit.

use rayon::prelude::*;

/// a · b with eight independent partial sums, so that the loop vectorizes (a plain sum fixes
/// the order of the additions and stays scalar); the Uzawa and residual loops live on it.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut lanes = [0.0; 8];
    let mut chunks_a = a.chunks_exact(8);
    let mut chunks_b = b.chunks_exact(8);
    for (ca, cb) in (&mut chunks_a).zip(&mut chunks_b) {
        for k in 0..8 {
            lanes[k] += ca[k] * cb[k];
        }
    }
    let tail: f64 = chunks_a
        .remainder()
        .iter()
        .zip(chunks_b.remainder())
        .map(|(x, y)| x * y)
        .sum();
    lanes.iter().sum::<f64>() + tail
}

/// |v|, summed in order: the norm of a node's tangent-coordinate vector (one to three entries).
pub fn norm2(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// max_i |a_i − b_i|.
pub fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0, |m, (x, y)| m.max((x - y).abs()))
}

/// The largest eigenvalue in modulus of the n × n operator `apply` (y = C v), by power
/// iteration from a fixed start, stopping when the estimate settles to 10⁻⁶ or after 200
/// products.
pub fn largest_eigenvalue<E>(n: usize, apply: impl FnMut(&[f64], &mut [f64]) -> Result<(), E>) -> Result<f64, E> {
    largest_eigenvalue_within(n, 1e-6, 200, apply)
}

/// [`largest_eigenvalue`] stopping when the estimate settles to `tolerance` (relative) or after
/// `max_products` products.
pub fn largest_eigenvalue_within<E>(
    n: usize,
    tolerance: f64,
    max_products: usize,
    mut apply: impl FnMut(&[f64], &mut [f64]) -> Result<(), E>,
) -> Result<f64, E> {
    if n == 0 {
        return Ok(0.0);
    }
    let mut v: Vec<f64> = (0..n).map(|i| 1.0 + 0.1 * (i % 7) as f64).collect();
    let mut y = vec![0.0; n];
    let mut estimate = 0.0;
    for _ in 0..max_products {
        let norm = dot(&v, &v).sqrt();
        v.iter_mut().for_each(|x| *x /= norm);
        apply(&v, &mut y)?;
        let new = dot(&y, &y).sqrt();
        let settled = (new - estimate).abs() <= tolerance * new;
        estimate = new;
        std::mem::swap(&mut v, &mut y);
        if settled {
            break;
        }
    }
    Ok(estimate)
}

/// Entries per block of the vector operations: the blocks' partial sums are computed in
/// parallel and added in block order, so a dot product is the same to the bit on any number of
/// threads.
const VECTOR_BLOCK: usize = 16_384;

/// Vectors up to this length (8 blocks) are swept on the calling thread, by the same blocks
/// (the same bits): a block's dot product takes microseconds, about what handing it to another
/// thread costs. Measured on the 3D example at 47k unknowns and k = 1/8 (`bench --hard`'s
/// iterative case: 646 solves, 11 GMRES iterations each, so hundreds of inner products per
/// solve), two interleaved pairs: 12.5–12.6 s of solves with every block on the pool, 11.5–12.0 s
/// with these on the calling thread; at k = 1/64 (3 iterations per solve) within the noise.
const SEQUENTIAL_UP_TO: usize = 8 * VECTOR_BLOCK;

/// a · b, by blocks (`VECTOR_BLOCK`), in parallel above `SEQUENTIAL_UP_TO` entries: the blocks'
/// sums added in block order, so the same to the bit on any number of threads (the Krylov
/// solver's inner products).
pub fn par_dot(a: &[f64], b: &[f64]) -> f64 {
    blocked_dot(a, b, a.len() > SEQUENTIAL_UP_TO)
}

/// [`par_dot`]'s blocks, on rayon's pool or on the calling thread.
fn blocked_dot(a: &[f64], b: &[f64], parallel: bool) -> f64 {
    let block = |(x, y): (&[f64], &[f64])| {
        let mut acc = [0.0; 4];
        let (x4, y4) = (x.chunks_exact(4), y.chunks_exact(4));
        let tail: f64 = x4.remainder().iter().zip(y4.remainder()).map(|(p, q)| p * q).sum();
        for (p, q) in x4.zip(y4) {
            for k in 0..4 {
                acc[k] += p[k] * q[k];
            }
        }
        (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
    };
    if !parallel {
        return a.chunks(VECTOR_BLOCK).zip(b.chunks(VECTOR_BLOCK)).map(block).sum();
    }
    let partials: Vec<f64> = a
        .par_chunks(VECTOR_BLOCK)
        .zip(b.par_chunks(VECTOR_BLOCK))
        .map(block)
        .collect();
    partials.iter().sum()
}

/// y += alpha x, by blocks in parallel above `SEQUENTIAL_UP_TO` entries.
pub fn par_axpy(alpha: f64, x: &[f64], y: &mut [f64]) {
    if y.len() <= SEQUENTIAL_UP_TO {
        y.iter_mut().zip(x).for_each(|(y, x)| *y += alpha * x);
        return;
    }
    y.par_chunks_mut(VECTOR_BLOCK)
        .zip(x.par_chunks(VECTOR_BLOCK))
        .for_each(|(y, x)| y.iter_mut().zip(x).for_each(|(y, x)| *y += alpha * x));
}

/// ‖a‖ from [`par_dot`].
pub fn par_norm(a: &[f64]) -> f64 {
    par_dot(a, a).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The blocks of a dot product summed on the calling thread or on the pool: the same bits.
    #[test]
    fn a_dot_product_is_the_same_on_the_calling_thread_and_on_the_pool() {
        let n = 5 * VECTOR_BLOCK + 7;
        let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() * 1e3).collect();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos() / 7.0).collect();
        let (here, pooled) = (blocked_dot(&a, &b, false), blocked_dot(&a, &b, true));
        assert_eq!(here.to_bits(), pooled.to_bits());
        assert_eq!(par_dot(&a, &b).to_bits(), here.to_bits());
    }
}
