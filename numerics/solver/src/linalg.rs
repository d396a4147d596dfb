//! Solving the small linear systems of Rosenbrock methods, on fixed-size arrays.

/// Solves `a x = b` by Gaussian elimination with partial pivoting;
/// `None` if `a` is singular.
pub fn solve<const N: usize>(mut a: [[f64; N]; N], mut b: [f64; N]) -> Option<[f64; N]> {
    for col in 0..N {
        let pivot = (col..N).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col] == 0.0 || !a[pivot][col].is_finite() {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        for row in col + 1..N {
            let factor = a[row][col] / a[col][col];
            for k in col..N {
                a[row][k] -= factor * a[col][k];
            }
            b[row] -= factor * b[col];
        }
    }
    let mut x = [0.0; N];
    for row in (0..N).rev() {
        let tail: f64 = (row + 1..N).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - tail) / a[row][row];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    #[test]
    fn solves_a_pivoting_system() {
        let x = super::solve([[0.0, 2.0], [3.0, 1.0]], [4.0, 5.0]).unwrap();
        assert!((x[0] - 1.0).abs() < 1e-15 && (x[1] - 2.0).abs() < 1e-15);
        assert!(super::solve([[1.0, 2.0], [2.0, 4.0]], [1.0, 1.0]).is_none());
    }
}

/// `exp(a)` of a small matrix: scaled until its norm is at most 1/2, a
/// Taylor series to 18 terms (remainder below 1e-20), then squared back.
pub fn expm<const N: usize>(a: [[f64; N]; N]) -> [[f64; N]; N] {
    let norm = a.iter().map(|row| row.iter().map(|x| x.abs()).sum::<f64>()).fold(0.0, f64::max);
    let mut squarings = 0;
    let mut scale = 1.0;
    while norm * scale > 0.5 && squarings < 1100 {
        scale *= 0.5;
        squarings += 1;
    }
    let mut x = [[0.0; N]; N];
    for i in 0..N {
        for j in 0..N {
            x[i][j] = a[i][j] * scale;
        }
    }
    let mut sum = identity::<N>();
    let mut term = identity::<N>();
    for k in 1..=18 {
        term = product(&term, &x);
        for i in 0..N {
            for j in 0..N {
                term[i][j] /= k as f64;
                sum[i][j] += term[i][j];
            }
        }
    }
    for _ in 0..squarings {
        sum = product(&sum, &sum);
    }
    sum
}

fn identity<const N: usize>() -> [[f64; N]; N] {
    let mut m = [[0.0; N]; N];
    for (i, row) in m.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    m
}

fn product<const N: usize>(a: &[[f64; N]; N], b: &[[f64; N]; N]) -> [[f64; N]; N] {
    let mut m = [[0.0; N]; N];
    for i in 0..N {
        for k in 0..N {
            for j in 0..N {
                m[i][j] += a[i][k] * b[k][j];
            }
        }
    }
    m
}

#[cfg(test)]
mod expm_tests {
    use super::expm;

    #[test]
    fn rotation_and_decay_match_their_closed_forms() {
        // exp([[0, w], [-w, 0]] t) is a rotation by w*t.
        let (w, t) = (3.0, 7.0);
        let e = expm([[0.0, w * t], [-w * t, 0.0]]);
        let (c, s) = ((w * t).cos(), (w * t).sin());
        for (got, want) in [(e[0][0], c), (e[0][1], s), (e[1][0], -s), (e[1][1], c)] {
            assert!((got - want).abs() < 1e-13, "{got} {want}");
        }
        // A nilpotent part: exp([[0, 1], [0, 0]]) = [[1, 1], [0, 1]] exactly.
        assert_eq!(expm([[0.0, 1.0], [0.0, 0.0]]), [[1.0, 1.0], [0.0, 1.0]]);
        let d = expm([[-40.0]]);
        assert!((d[0][0] / (-40.0f64).exp() - 1.0).abs() < 1e-12);
    }
}
