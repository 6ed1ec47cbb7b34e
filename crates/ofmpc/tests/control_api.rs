//! Settings, construction and error handling of the controllers: bad input is
//! a clear error, and a failed step leaves the controller's state untouched.

mod common;

use common::CoupledModel;
use nalgebra::{DMatrix, DVector};
use ofmpc::control::{
    new_controller, Algorithm, ControllerKind, MpcSettings, SettingsError, StepFailure, TermsError,
    Weight, ZohError,
};
use ofmpc::dynamics::JointSpaceDynamics;

#[derive(Clone, Copy, PartialEq)]
enum Fault {
    None,
    Indefinite,
    NanGravity,
    HugeCoriolis,
}

/// A model that can be made to misbehave.
struct Faulty {
    inner: CoupledModel,
    fault: Fault,
}

impl JointSpaceDynamics for Faulty {
    fn dof(&self) -> usize {
        self.inner.dof()
    }
    fn terms(
        &mut self,
        q: &[f64],
        qd: &[f64],
        h: &mut DMatrix<f64>,
        c: &mut DMatrix<f64>,
        g: &mut DVector<f64>,
    ) {
        self.inner.terms(q, qd, h, c, g);
        match self.fault {
            Fault::None => {}
            Fault::Indefinite => h[(1, 1)] = -1.0,
            Fault::NanGravity => g[0] = f64::NAN,
            Fault::HugeCoriolis => c[(0, 0)] = 1e30,
        }
    }
}

#[test]
fn defaults_are_the_papers_tuning() {
    let s = MpcSettings::default();
    assert_eq!(s.ts, 0.01);
    assert_eq!(s.horizon, 10);
    assert_eq!(s.q_yw, Weight::Scalar(1.0));
    assert_eq!(s.q_dy, Weight::Scalar(0.5));
    assert_eq!(s.q_du, Weight::Scalar(1e-5));
    assert_eq!(s.q_u, Weight::Scalar(1e-4));
    assert!(s.validate().is_ok());
    assert!(s.validate_for_dof(6).is_ok());
}

#[test]
fn settings_parse_from_toml_with_scalars_diagonals_and_defaults() {
    let s: MpcSettings =
        toml::from_str("horizon = 20\nq_yw = 2.0\nq_dy = [0.1, 0.2, 0.3]\n").unwrap();
    assert_eq!(s.horizon, 20);
    assert_eq!(s.ts, 0.01);
    assert_eq!(s.q_yw, Weight::Scalar(2.0));
    assert_eq!(s.q_dy, Weight::Diagonal(vec![0.1, 0.2, 0.3]));
    assert_eq!(s.q_du, Weight::Scalar(1e-5));
    assert!(s.validate_for_dof(3).is_ok());
    assert_eq!(
        s.validate_for_dof(6),
        Err(SettingsError::WeightLength {
            name: "q_dy",
            expected: 6,
            got: 3
        })
    );
    // Round trip through TOML.
    let back: MpcSettings = toml::from_str(&toml::to_string(&s).unwrap()).unwrap();
    assert_eq!(back, s);
    let e = toml::from_str::<MpcSettings>("horizont = 5").unwrap_err();
    assert!(e.to_string().contains("horizont"), "{e}");
    assert!(toml::from_str::<MpcSettings>("q_yw = \"big\"").is_err());

    #[derive(serde::Deserialize)]
    struct K {
        kind: Vec<ControllerKind>,
    }
    let k: K = toml::from_str("kind = [\"usual\", \"first\", \"second\"]").unwrap();
    assert_eq!(k.kind, ControllerKind::PAPER);
    assert!(toml::from_str::<K>("kind = [\"Usual\"]").is_err());
    for kind in ControllerKind::PAPER {
        assert_eq!(kind.to_string().parse::<ControllerKind>().unwrap(), kind);
    }
    assert!("third"
        .parse::<ControllerKind>()
        .unwrap_err()
        .to_string()
        .contains("usual"));
}

#[test]
fn invalid_settings_are_rejected_with_the_field_named() {
    let base = MpcSettings::default();
    let cases: Vec<(MpcSettings, &str)> = vec![
        (
            MpcSettings {
                ts: 0.0,
                ..base.clone()
            },
            "ts",
        ),
        (
            MpcSettings {
                ts: f64::NAN,
                ..base.clone()
            },
            "ts",
        ),
        (
            MpcSettings {
                horizon: 0,
                ..base.clone()
            },
            "horizon",
        ),
        (
            MpcSettings {
                horizon: 100_000,
                ..base.clone()
            },
            "horizon",
        ),
        (
            MpcSettings {
                q_yw: Weight::Scalar(-1.0),
                ..base.clone()
            },
            "q_yw",
        ),
        (
            MpcSettings {
                q_dy: Weight::Diagonal(vec![0.5, f64::INFINITY]),
                ..base.clone()
            },
            "q_dy[1]",
        ),
        (
            MpcSettings {
                q_du: Weight::Scalar(0.0),
                ..base.clone()
            },
            "q_du",
        ),
        (
            MpcSettings {
                q_u: Weight::Scalar(0.0),
                ..base.clone()
            },
            "q_u",
        ),
        (
            MpcSettings {
                q_du: Weight::Diagonal(vec![]),
                ..base.clone()
            },
            "q_du",
        ),
        (
            MpcSettings {
                q_yw: Weight::Diagonal(vec![1.0; 2]),
                q_dy: Weight::Diagonal(vec![1.0; 3]),
                ..base.clone()
            },
            "q_dy",
        ),
    ];
    for (s, field) in cases {
        let e = s.validate().unwrap_err();
        assert!(e.to_string().contains(field), "{field}: {e}");
        for kind in ControllerKind::PAPER {
            assert!(new_controller(kind, 2, &s).is_err());
        }
    }
    assert_eq!(base.validate_for_dof(0), Err(SettingsError::ZeroDof));
    assert!(new_controller(ControllerKind::First, 0, &base).is_err());
    // Too large to allocate: a clear error, not an abort.
    let big = MpcSettings {
        horizon: 1000,
        ..base
    };
    assert!(matches!(
        new_controller(ControllerKind::Second, 200, &big),
        Err(SettingsError::TooLarge { .. })
    ));
}

#[test]
fn controllers_are_object_safe_and_send() {
    let s = MpcSettings::default();
    let boxed: Vec<Box<dyn Algorithm + Send>> = ControllerKind::PAPER
        .iter()
        .map(|&k| new_controller(k, 3, &s).unwrap())
        .collect();
    let handle = std::thread::spawn(move || {
        boxed
            .iter()
            .map(|c| (c.kind(), c.dof(), c.horizon(), c.settings().horizon))
            .collect::<Vec<_>>()
    });
    let got = handle.join().unwrap();
    assert_eq!(got.len(), 3);
    for ((kind, dof, nh, snh), want) in got.into_iter().zip(ControllerKind::PAPER) {
        assert_eq!((kind, dof, nh, snh), (want, 3, 10, 10));
    }
}

/// A bad call between good ones must not change what the controller does.
#[test]
fn failed_steps_report_errors_and_leave_the_state_untouched() {
    let n = 3;
    let s = MpcSettings::default();
    for kind in ControllerKind::PAPER {
        let mut good = new_controller(kind, n, &s).unwrap();
        let mut twin = new_controller(kind, n, &s).unwrap();
        let mut model = Faulty {
            inner: CoupledModel::new(n, 5),
            fault: Fault::None,
        };
        let x0 = [0.1, -0.2, 0.3, 0.0, 0.1, -0.1];
        good.reset(&x0).unwrap();
        twin.reset(&x0).unwrap();
        let wk = [0.2; 3];
        let preview = vec![0.25; s.horizon * n];
        let states: Vec<Vec<f64>> = (0..6)
            .map(|k| x0.iter().map(|v| v + 0.01 * k as f64).collect())
            .collect();
        let mut t_good = vec![0.0; n];
        let mut t_twin = vec![0.0; n];
        for (k, x) in states.iter().enumerate() {
            good.step(
                &mut model,
                &ofmpc::control::StepInput {
                    x,
                    w_k: &wk,
                    preview: &preview,
                },
                &mut t_good,
            )
            .unwrap();
            if k == 2 {
                let sentinel = vec![7.0; n];
                let mut t = sentinel.clone();
                let short = &x[..5];
                let e = twin
                    .step(
                        &mut model,
                        &ofmpc::control::StepInput {
                            x: short,
                            w_k: &wk,
                            preview: &preview,
                        },
                        &mut t,
                    )
                    .unwrap_err();
                assert!(
                    matches!(
                        e,
                        StepFailure::WrongLength {
                            what: "x",
                            expected: 6,
                            got: 5
                        }
                    ),
                    "{e}"
                );
                let e = twin
                    .step(
                        &mut model,
                        &ofmpc::control::StepInput {
                            x,
                            w_k: &wk[..2],
                            preview: &preview,
                        },
                        &mut t,
                    )
                    .unwrap_err();
                assert!(
                    matches!(e, StepFailure::WrongLength { what: "w_k", .. }),
                    "{e}"
                );
                let e = twin
                    .step(
                        &mut model,
                        &ofmpc::control::StepInput {
                            x,
                            w_k: &wk,
                            preview: &preview[1..],
                        },
                        &mut t,
                    )
                    .unwrap_err();
                assert!(
                    matches!(
                        e,
                        StepFailure::WrongLength {
                            what: "preview",
                            ..
                        }
                    ),
                    "{e}"
                );
                let e = twin
                    .step(
                        &mut model,
                        &ofmpc::control::StepInput {
                            x,
                            w_k: &wk,
                            preview: &preview,
                        },
                        &mut [0.0; 2],
                    )
                    .unwrap_err();
                assert!(
                    matches!(e, StepFailure::WrongLength { what: "tau", .. }),
                    "{e}"
                );
                let mut bad_x = x.clone();
                bad_x[4] = f64::NAN;
                let e = twin
                    .step(
                        &mut model,
                        &ofmpc::control::StepInput {
                            x: &bad_x,
                            w_k: &wk,
                            preview: &preview,
                        },
                        &mut t,
                    )
                    .unwrap_err();
                assert_eq!(
                    e,
                    StepFailure::NonFiniteInput {
                        what: "x",
                        index: 4
                    }
                );
                let mut bad_w = preview.clone();
                bad_w[7] = f64::INFINITY;
                let e = twin
                    .step(
                        &mut model,
                        &ofmpc::control::StepInput {
                            x,
                            w_k: &wk,
                            preview: &bad_w,
                        },
                        &mut t,
                    )
                    .unwrap_err();
                assert_eq!(
                    e,
                    StepFailure::NonFiniteInput {
                        what: "preview",
                        index: 7
                    }
                );
                for (fault, want) in [
                    (Fault::Indefinite, "positive definite"),
                    (Fault::NanGravity, "g[0]"),
                    (Fault::HugeCoriolis, "f0·Ts"),
                ] {
                    model.fault = fault;
                    let e = twin
                        .step(
                            &mut model,
                            &ofmpc::control::StepInput {
                                x,
                                w_k: &wk,
                                preview: &preview,
                            },
                            &mut t,
                        )
                        .unwrap_err();
                    assert!(e.to_string().contains(want), "{kind}: {e}");
                    match fault {
                        Fault::Indefinite => {
                            assert!(matches!(
                                e,
                                StepFailure::Model(TermsError::InertiaNotPositiveDefinite {
                                    pivot: 1,
                                    ..
                                })
                            ))
                        }
                        Fault::NanGravity => assert!(matches!(
                            e,
                            StepFailure::Model(TermsError::NonFiniteTerm { .. })
                        )),
                        _ => assert!(matches!(
                            e,
                            StepFailure::Discretization(ZohError::BadNorm { .. })
                        )),
                    }
                    model.fault = Fault::None;
                }
                let mut wrong = CoupledModel::new(2, 1);
                let e = twin
                    .step(
                        &mut wrong,
                        &ofmpc::control::StepInput {
                            x,
                            w_k: &wk,
                            preview: &preview,
                        },
                        &mut t,
                    )
                    .unwrap_err();
                assert!(matches!(
                    e,
                    StepFailure::Model(TermsError::DofMismatch {
                        expected: 3,
                        got: 2
                    })
                ));
                assert_eq!(t, sentinel, "tau must not be written on error");
            }
            twin.step(
                &mut model,
                &ofmpc::control::StepInput {
                    x,
                    w_k: &wk,
                    preview: &preview,
                },
                &mut t_twin,
            )
            .unwrap();
            assert_eq!(
                t_good, t_twin,
                "{kind}: step {k} differs after failed calls"
            );
            assert_eq!(good.input(), twin.input());
        }
        // reset checks its input too
        assert!(matches!(
            good.reset(&x0[..4]),
            Err(StepFailure::WrongLength { what: "x0", .. })
        ));
        assert!(matches!(
            good.reset(&[f64::NAN; 6]),
            Err(StepFailure::NonFiniteInput {
                what: "x0",
                index: 0
            })
        ));
        good.reset(&x0).unwrap();
        assert_eq!(good.input(), &[0.0; 3]);
    }
}

#[test]
fn reset_restarts_from_scratch() {
    let n = 2;
    let s = MpcSettings {
        horizon: 4,
        ..MpcSettings::default()
    };
    for kind in ControllerKind::PAPER {
        let mut c = new_controller(kind, n, &s).unwrap();
        let mut model = CoupledModel::new(n, 2);
        let x0 = [0.1, 0.2, 0.0, 0.0];
        let (wk, preview) = ([0.3, 0.1], vec![0.3, 0.1, 0.3, 0.1, 0.3, 0.1, 0.3, 0.1]);
        c.reset(&x0).unwrap();
        let mut first = [0.0; 2];
        c.step(
            &mut model,
            &ofmpc::control::StepInput {
                x: &x0,
                w_k: &wk,
                preview: &preview,
            },
            &mut first,
        )
        .unwrap();
        let mut t = [0.0; 2];
        for _ in 0..5 {
            c.step(
                &mut model,
                &ofmpc::control::StepInput {
                    x: &[0.2, 0.1, 0.5, -0.3],
                    w_k: &wk,
                    preview: &preview,
                },
                &mut t,
            )
            .unwrap();
        }
        c.reset(&x0).unwrap();
        c.step(
            &mut model,
            &ofmpc::control::StepInput {
                x: &x0,
                w_k: &wk,
                preview: &preview,
            },
            &mut t,
        )
        .unwrap();
        assert_eq!(t, first, "{kind}");
    }
}

/// Issue 9 item 17: one size limit, stated once: a horizon the dense solver
/// cannot hold is rejected by validation, with the same error the
/// constructor would give; the structured solver takes it.
#[test]
fn horizon_size_limit_is_checked_by_validation() {
    use ofmpc::control::{new_controller, ControllerKind, MpcSettings, SettingsError, Solver};
    let dense = MpcSettings {
        horizon: 1000,
        solver: Solver::DenseQr,
        ..MpcSettings::default()
    };
    let e = dense.validate_for_dof(6).unwrap_err();
    assert!(
        matches!(
            e,
            SettingsError::TooLarge {
                rows: 12000,
                cols: 6000,
                ..
            }
        ),
        "{e:?}"
    );
    let built = new_controller(ControllerKind::Usual, 6, &dense).err();
    assert_eq!(built, Some(e));
    let structured = MpcSettings {
        solver: Solver::Structured,
        ..dense.clone()
    };
    structured.validate_for_dof(6).unwrap();
    let auto = MpcSettings {
        solver: Solver::Auto,
        ..dense
    };
    auto.validate_for_dof(6).unwrap();
}

/// Issue #22 item 17: the structured solver's size error does not advise the structured
/// solver (it advises the horizons); the dense solver's still does.
#[test]
fn a_size_error_advises_what_fits_its_solver() {
    use ofmpc::control::{MpcSettings, SettingsError, Solver};
    let structured = MpcSettings {
        horizon: 1000,
        solver: Solver::Structured,
        torque_limits: true,
        ..MpcSettings::default()
    };
    let e = structured.validate_for_dof(200).unwrap_err();
    assert!(
        matches!(
            e,
            SettingsError::TooLarge {
                solver: Solver::Structured,
                ..
            }
        ),
        "{e:?}"
    );
    let text = e.to_string();
    assert!(!text.contains("use the structured solver"), "{text}");
    assert!(text.contains("constraint horizon"), "{text}");
    let dense = MpcSettings {
        horizon: 1000,
        solver: Solver::DenseQr,
        ..MpcSettings::default()
    };
    let text = dense.validate_for_dof(6).unwrap_err().to_string();
    assert!(text.contains("use the structured solver"), "{text}");
}
