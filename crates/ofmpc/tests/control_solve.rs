//! Each controller's step against a brute-force build of the paper's
//! unpermuted system (37), (39), (43) from independently computed matrices,
//! solved by SVD: same applied input, same J_min.

mod common;

use common::{brute, zoh_reference, Brute, CoupledModel, Plant, Rng};
use nalgebra::{DMatrix, DVector};
use ofmpc::control::{new_controller, ControllerKind, MpcSettings, Weight};
use ofmpc::dynamics::JointSpaceDynamics;

fn block_diag(d: &[f64], nh: usize) -> DMatrix<f64> {
    DMatrix::from_diagonal(&DVector::from_fn(nh * d.len(), |i, _| d[i % d.len()]))
}

#[allow(clippy::too_many_arguments)]
fn paper_system(
    kind: ControllerKind,
    b: &Brute,
    n: usize,
    nh: usize,
    s: (&[f64], &[f64], &[f64], &[f64]),
    x: &DVector<f64>,
    dx: &DVector<f64>,
    ebar: &DVector<f64>,
    w: &DVector<f64>,
) -> (DMatrix<f64>, DVector<f64>) {
    let (qyw, qdy, qdu, qu) = (
        block_diag(s.0, nh),
        block_diag(s.1, nh),
        block_diag(s.2, nh),
        block_diag(s.3, nh),
    );
    let p = nh * n;
    let y = x.rows(0, n).into_owned();
    let fi = DMatrix::from_fn(p, n, |i, j| if i % n == j { 1.0 } else { 0.0 });
    let fii = DMatrix::from_fn(p, n, |i, j| if i % n == j { (i / n) as f64 } else { 0.0 });
    let ws = DVector::from_fn(p, |i, _| {
        (0..i / n).map(|jj| w[jj * n + i % n]).sum::<f64>()
    });
    match kind {
        ControllerKind::Usual => {
            let mut a = DMatrix::<f64>::zeros(2 * p, p);
            a.view_mut((0, 0), (p, p)).copy_from(&(&qyw * &b.g1));
            a.view_mut((p, 0), (p, p)).copy_from(&qu);
            let mut r = DVector::<f64>::zeros(2 * p);
            r.rows_mut(0, p).copy_from(&(&qyw * (w - &b.f1 * x)));
            (a, r)
        }
        _ => {
            let second = kind.base() == ControllerKind::Second;
            let top = if second { &b.g2 + &b.g3 } else { b.g2.clone() };
            let mut a = DMatrix::<f64>::zeros(3 * p, p);
            a.view_mut((0, 0), (p, p)).copy_from(&(&qyw * top));
            a.view_mut((p, 0), (p, p)).copy_from(&(&qdy * &b.g1));
            a.view_mut((2 * p, 0), (p, p)).copy_from(&qdu);
            let rtop = if second {
                w + &ws + &fi * ebar - (&fi + &fii) * &y - (&b.f2 + &b.f3) * dx
            } else {
                w - &fi * &y - &b.f2 * dx
            };
            let mut r = DVector::<f64>::zeros(3 * p);
            r.rows_mut(0, p).copy_from(&(&qyw * rtop));
            r.rows_mut(p, p).copy_from(&(-(&qdy * &b.f1 * dx)));
            (a, r)
        }
    }
}

#[test]
fn steps_solve_the_papers_least_squares_systems() {
    let n = 3;
    for kind in ControllerKind::PAPER {
        for &nh in &[1usize, 2, 5, 10] {
            let settings = MpcSettings {
                horizon: nh,
                q_yw: Weight::Diagonal(vec![1.0, 2.0, 0.7]),
                q_dy: Weight::Diagonal(vec![0.5, 0.3, 0.9]),
                q_du: Weight::Scalar(1e-3),
                q_u: Weight::Diagonal(vec![1e-2, 3e-3, 1e-2]),
                ..MpcSettings::default()
            };
            let sq = |w: &Weight| (0..n).map(|i| w.get(i).unwrap()).collect::<Vec<_>>();
            let (qyw, qdy, qdu, qu) = (
                sq(&settings.q_yw),
                sq(&settings.q_dy),
                sq(&settings.q_du),
                sq(&settings.q_u),
            );
            let mut model = CoupledModel::new(n, 17);
            let mut plant = Plant::new(CoupledModel::new(n, 17), DVector::from_element(n, 0.4), 4);
            let mut ctrl = new_controller(kind, n, &settings).unwrap();
            let mut rng = Rng(100 + nh as u64);
            let mut x = DVector::from_fn(2 * n, |i, _| {
                if i < n {
                    0.3 * rng.next()
                } else {
                    0.5 * rng.next()
                }
            });
            ctrl.reset(x.as_slice()).unwrap();
            let (mut x_prev, mut u_prev, mut ebar) = (
                x.clone(),
                DVector::<f64>::zeros(n),
                DVector::<f64>::zeros(n),
            );
            let (mut h, mut c, mut g) = (
                DMatrix::<f64>::zeros(n, n),
                DMatrix::<f64>::zeros(n, n),
                DVector::<f64>::zeros(n),
            );
            for k in 0..8 {
                let wk = DVector::from_fn(n, |_, _| 0.5 * rng.next());
                let w = DVector::from_fn(nh * n, |_, _| 0.5 * rng.next());
                let mut tau = vec![0.0; n];
                let info = ctrl
                    .step(
                        &mut model,
                        &ofmpc::control::StepInput {
                            x: x.as_slice(),
                            w_k: wk.as_slice(),
                            preview: w.as_slice(),
                        },
                        &mut tau,
                    )
                    .unwrap();
                // Brute force at the same state.
                model.terms(
                    &x.as_slice()[..n],
                    &x.as_slice()[n..],
                    &mut h,
                    &mut c,
                    &mut g,
                );
                let f0 = -h.clone().lu().solve(&c).unwrap();
                let (ad, bd) = zoh_reference(&f0, settings.ts);
                let bm = brute(&ad, &bd, n, nh);
                let dx = &x - &x_prev;
                let y = x.rows(0, n).into_owned();
                let ebar_k = &ebar + (&wk - &y);
                let (a, r) = paper_system(
                    kind,
                    &bm,
                    n,
                    nh,
                    (&qyw, &qdy, &qdu, &qu),
                    &x,
                    &dx,
                    &ebar_k,
                    &w,
                );
                let sol = a.clone().svd(true, true).solve(&r, 0.0).unwrap();
                let jmin = (&a * &sol - &r).norm_squared();
                let first = sol.rows(0, n).into_owned();
                let u_want = if kind == ControllerKind::Usual {
                    first
                } else {
                    &u_prev + first
                };
                let u_got = h
                    .clone()
                    .lu()
                    .solve(&(DVector::from_column_slice(&tau) - &g))
                    .unwrap();
                let err = (&u_got - &u_want).norm() / u_want.norm().max(1e-12);
                assert!(
                    err < 1e-8,
                    "{kind} N={nh} k={k}: u err {err:e}, got {u_got} want {u_want}"
                );
                let cerr = (info.cost - jmin).abs() / jmin.max(1e-300);
                assert!(
                    cerr < 1e-8,
                    "{kind} N={nh} k={k}: J_min {} vs {jmin}",
                    info.cost
                );
                assert!(
                    (DVector::from_column_slice(ctrl.input()) - &u_got).norm()
                        < 1e-9 * u_got.norm().max(1.0)
                );
                // Advance the bookkeeping and the plant.
                x_prev = x.clone();
                u_prev = u_want;
                ebar = ebar_k;
                plant.advance(&mut x, &tau, settings.ts);
            }
        }
    }
}

/// The test models are valid robot models: `H` SPD and `Ḣ − 2C` skew
/// (finite differences of `H` along `q̇`).
#[test]
fn test_models_are_christoffel_consistent() {
    let mut models: Vec<Box<dyn JointSpaceDynamics>> = vec![
        Box::new(CoupledModel::new(4, 3)),
        Box::new(common::TwoLinkArm::new()),
    ];
    for model in &mut models {
        let n = model.dof();
        let mut rng = Rng(8);
        let q: Vec<f64> = (0..n).map(|_| rng.next()).collect();
        let qd: Vec<f64> = (0..n).map(|_| rng.next()).collect();
        let (mut h, mut c, mut g) = (
            DMatrix::<f64>::zeros(n, n),
            DMatrix::<f64>::zeros(n, n),
            DVector::<f64>::zeros(n),
        );
        let (mut hp, mut hm) = (h.clone(), h.clone());
        let eps = 1e-6;
        let qp: Vec<f64> = q.iter().zip(&qd).map(|(a, b)| a + eps * b).collect();
        let qm: Vec<f64> = q.iter().zip(&qd).map(|(a, b)| a - eps * b).collect();
        model.terms(&qp, &qd, &mut hp, &mut c, &mut g);
        model.terms(&qm, &qd, &mut hm, &mut c, &mut g);
        model.terms(&q, &qd, &mut h, &mut c, &mut g);
        let hdot = (hp - hm) / (2.0 * eps);
        let n_mat = &hdot - &c * 2.0;
        assert!((&n_mat + n_mat.transpose()).norm() < 1e-8 * hdot.norm().max(1.0));
        assert!(h.clone().cholesky().is_some());
        assert!(c.norm() > 0.0);
    }
}
