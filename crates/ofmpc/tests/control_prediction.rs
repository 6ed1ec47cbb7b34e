//! Prediction matrices of Eq. (20)–(29) and the positional F, G of Eq. (43)
//! against brute-force rollouts of the incremental model (19) and the
//! positional model (16).

mod common;

use common::{zoh_reference, Rng};
use nalgebra::{DMatrix, DVector};
use ofmpc::control::Zoh;
use ofmpc::control::{fill_f_i, fill_f_ii, fill_w_s, Predictions};

fn rel(a: &DVector<f64>, b: &DVector<f64>, scale: f64) -> f64 {
    (a - b).norm() / scale.max(1e-300)
}

struct Full {
    f1: DMatrix<f64>,
    f2: DMatrix<f64>,
    f3: DMatrix<f64>,
    g1: DMatrix<f64>,
    g2: DMatrix<f64>,
    g3: DMatrix<f64>,
}

fn full(p: &Predictions, ny: usize, nu: usize, nh: usize) -> Full {
    let mut g = [
        DMatrix::zeros(nh * ny, nh * nu),
        DMatrix::zeros(nh * ny, nh * nu),
        DMatrix::zeros(nh * ny, nh * nu),
    ];
    p.fill_toeplitz(p.g1_gen(), &mut g[0]).unwrap();
    p.fill_toeplitz(p.g2_gen(), &mut g[1]).unwrap();
    p.fill_toeplitz(p.g3_gen(), &mut g[2]).unwrap();
    let [g1, g2, g3] = g;
    Full {
        f1: p.f1().clone(),
        f2: p.f2().clone(),
        f3: p.f3().clone(),
        g1,
        g2,
        g3,
    }
}

#[test]
fn incremental_and_positional_predictions_match_rollouts() {
    let mut rng = Rng(42);
    for &(nx, nu, ny) in &[(2, 1, 1), (4, 2, 2), (6, 3, 3), (5, 2, 3)] {
        for &nh in &[1usize, 2, 3, 7, 10] {
            for trial in 0..3 {
                // ‖A‖ ≈ 1 so that powers neither vanish nor explode over N.
                let a0 = rng.matrix(nx, nx);
                let a = &a0 * (1.0 / a0.norm() * (nx as f64).sqrt() * 0.8);
                let b = rng.matrix(nx, nu);
                let c = if trial == 0 && ny * 2 == nx {
                    // the model's C = [I, 0]
                    let mut c = DMatrix::zeros(ny, nx);
                    c.view_mut((0, 0), (ny, ny)).fill_with_identity();
                    c
                } else {
                    rng.matrix(ny, nx)
                };
                let mut p = Predictions::new(nx, nu, ny, nh);
                p.update_from_state_space(&a, &b, &c).unwrap();
                let m = full(&p, ny, nu, nh);

                let dx = rng.vector(nx);
                let du = rng.vector(nh * nu);
                let xk = rng.vector(nx);
                let yk = &c * &xk;
                let ebar = rng.vector(ny);
                let w = rng.vector(nh * ny); // w_{k+1..k+N}

                // Rollout of (19): Δx_{k+j} = A Δx_{k+j-1} + B Δu_{k+j-1}.
                let mut dxi = dx.clone();
                let mut dy = DVector::zeros(nh * ny);
                let mut yhat = DVector::zeros(nh * ny);
                let mut ehat = DVector::zeros(nh * ny);
                let mut ysum = yk.clone();
                let mut e_acc = ebar.clone();
                for j in 0..nh {
                    dxi = &a * &dxi + &b * du.rows(j * nu, nu);
                    let dyj = &c * &dxi;
                    dy.rows_mut(j * ny, ny).copy_from(&dyj);
                    ysum += &dyj;
                    yhat.rows_mut(j * ny, ny).copy_from(&ysum);
                    // Ê block j (0-based) = ē_k + Σ_{i=1}^{j} (w_{k+i} − ŷ_{k+i})
                    ehat.rows_mut(j * ny, ny).copy_from(&e_acc);
                    e_acc += w.rows(j * ny, ny) - &ysum;
                }
                let scale = |v: &DVector<f64>| v.norm().max(1.0);
                // Eq. (22)
                let dy_p = &m.f1 * &dx + &m.g1 * &du;
                assert!(rel(&dy_p, &dy, scale(&dy)) < 1e-12, "ΔY nx={nx} N={nh}");
                // Eq. (25)
                let mut fi = DMatrix::zeros(nh * ny, ny);
                fill_f_i(ny, nh, &mut fi).unwrap();
                let y_p = &fi * &yk + &m.f2 * &dx + &m.g2 * &du;
                assert!(rel(&y_p, &yhat, scale(&yhat)) < 1e-12, "Ŷ nx={nx} N={nh}");
                // Eq. (28) with the minus sign of docs/guide/paper-notes.md ("Symbols")
                let mut fii = DMatrix::zeros(nh * ny, ny);
                fill_f_ii(ny, nh, &mut fii).unwrap();
                let mut ws = vec![0.0; nh * ny];
                fill_w_s(ny, w.as_slice(), &mut ws).unwrap();
                let ws = DVector::from_vec(ws);
                let e_p = &fi * &ebar + &ws - &fii * &yk - &m.f3 * &dx - &m.g3 * &du;
                assert!(rel(&e_p, &ehat, scale(&ehat)) < 1e-12, "Ê nx={nx} N={nh}");

                // Positional (16): x_{k+j} = A x_{k+j-1} + B u_{k+j-1}, Y = F x_k + G U.
                let u = rng.vector(nh * nu);
                let mut xi = xk.clone();
                let mut ypos = DVector::zeros(nh * ny);
                for j in 0..nh {
                    xi = &a * &xi + &b * u.rows(j * nu, nu);
                    ypos.rows_mut(j * ny, ny).copy_from(&(&c * &xi));
                }
                let ypos_p = &m.f1 * &xk + &m.g1 * &u;
                assert!(
                    rel(&ypos_p, &ypos, scale(&ypos)) < 1e-12,
                    "Y positional nx={nx} N={nh}"
                );
            }
        }
    }
}

#[test]
fn structured_zoh_predictions_equal_general_ones() {
    let mut rng = Rng(9);
    for &n in &[1usize, 2, 6] {
        for &nh in &[1usize, 3, 10, 20] {
            let f0 = rng.matrix(n, n) * 30.0;
            let ts = 0.01;
            let mut z = Zoh::new(n);
            z.discretize(&f0, ts).unwrap();
            let (ad, bd) = zoh_reference(&f0, ts);
            let mut c = DMatrix::zeros(n, 2 * n);
            c.view_mut((0, 0), (n, n)).fill_with_identity();
            let mut general = Predictions::new(2 * n, n, n, nh);
            general.update_from_state_space(&ad, &bd, &c).unwrap();
            let mut fast = Predictions::new(2 * n, n, n, nh);
            fast.update_from_zoh(&z).unwrap();
            for (name, x, y) in [
                ("F1", fast.f1(), general.f1()),
                ("F2", fast.f2(), general.f2()),
                ("F3", fast.f3(), general.f3()),
                ("G1", fast.g1_gen(), general.g1_gen()),
                ("G2", fast.g2_gen(), general.g2_gen()),
                ("G3", fast.g3_gen(), general.g3_gen()),
            ] {
                let e = (x - y).norm() / y.norm().max(1e-300);
                assert!(e < 1e-12, "{name}: n={n} N={nh}: {e:e}");
            }
        }
    }
}

#[test]
fn paper_block_formulas_hold() {
    // Spot-check the closed forms of docs/guide/paper-notes.md ("Symbols") on a
    // small random model.
    let mut rng = Rng(3);
    let (nx, nu, ny, nh) = (3, 2, 2, 5);
    let a = rng.matrix(nx, nx) * 0.5;
    let b = rng.matrix(nx, nu);
    let c = rng.matrix(ny, nx);
    let mut p = Predictions::new(nx, nu, ny, nh);
    p.update_from_state_space(&a, &b, &c).unwrap();
    let m = full(&p, ny, nu, nh);
    let pow = |k: usize| (0..k).fold(DMatrix::<f64>::identity(nx, nx), |acc, _| &acc * &a);
    let cab = |k: usize| &c * pow(k) * &b;
    for j in 1..=nh {
        let f3: DMatrix<f64> = (1..j).fold(DMatrix::zeros(ny, nx), |s, i| {
            s + &c * pow(i) * ((j - i) as f64)
        });
        let got = m.f3.view(((j - 1) * ny, 0), (ny, nx)).into_owned();
        assert!((got - f3).norm() < 1e-13);
        for l in 1..=nh {
            let blk =
                |g: &DMatrix<f64>| g.view(((j - 1) * ny, (l - 1) * nu), (ny, nu)).into_owned();
            let g2 = if l <= j {
                (l..=j).fold(DMatrix::zeros(ny, nu), |s, mm| s + cab(mm - l))
            } else {
                DMatrix::zeros(ny, nu)
            };
            let g3 = if l < j {
                (l..j).fold(DMatrix::zeros(ny, nu), |s, mm| {
                    s + cab(mm - l) * ((j - mm) as f64)
                })
            } else {
                DMatrix::zeros(ny, nu)
            };
            assert!((blk(&m.g2) - g2).norm() < 1e-13, "G2[{j},{l}]");
            assert!((blk(&m.g3) - g3).norm() < 1e-13, "G3[{j},{l}]");
        }
    }
}

#[test]
fn shape_errors_are_reported() {
    let mut p = Predictions::new(4, 2, 2, 3);
    let bad = DMatrix::zeros(3, 3);
    assert!(p
        .update_from_state_space(&bad, &DMatrix::zeros(4, 2), &DMatrix::zeros(2, 4))
        .is_err());
    let z = Zoh::new(3);
    assert!(p.update_from_zoh(&z).is_err());
    let mut out = vec![0.0; 5];
    assert!(fill_w_s(2, &[0.0; 6], &mut out).is_err());
    let mut out = vec![0.0; 6];
    assert!(fill_w_s(4, &[0.0; 6], &mut out).is_err());
    assert!(fill_f_i(2, 3, &mut DMatrix::zeros(5, 2)).is_err());
}
