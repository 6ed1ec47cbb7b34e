//! Parameters and expressions of rs274ngc (LinuxCNC's dialect, "G-code overview: parameters,
//! expressions, binary operators, functions"): `#n`, `#<name>`, `#<_global>`, `[ … ]` with
//! `** * / MOD + - EQ NE GT GE LT LE AND OR XOR` and the unary functions
//! `ABS ACOS ASIN ATAN[a]/[b] COS EXP FIX FUP LN ROUND SIN SQRT TAN EXISTS` (angles in degrees).
//!
//! Precedence, as LinuxCNC's `precedence()` (interp_read.cc): `**` binds tightest, then
//! `* / MOD`, then `+ -`, then the comparisons, then `AND OR XOR`; equal precedence groups to
//! the left.

use std::collections::HashMap;

/// Highest numbered parameter (LinuxCNC: `RS274NGC_MAX_PARAMETERS - 1`).
pub(super) const MAX_PARAMETER: usize = 5602;

/// An expression as read; evaluated when its line executes.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Expr {
    Num(f64),
    /// `#<expr>`: a numbered parameter.
    Param(Box<Expr>),
    /// `#<name>` (lower case, blanks removed).
    Named(String),
    /// `EXISTS[#<name>]`.
    Exists(String),
    Neg(Box<Expr>),
    Func(Func, Box<Expr>),
    Atan(Box<Expr>, Box<Expr>),
    Bin(Op, Box<Expr>, Box<Expr>),
}

/// A unary function.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Func {
    Abs,
    Acos,
    Asin,
    Cos,
    Exp,
    Fix,
    Fup,
    Ln,
    Round,
    Sin,
    Sqrt,
    Tan,
}

/// A binary operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Op {
    Pow,
    Mul,
    Div,
    Mod,
    Add,
    Sub,
    Eq,
    Ne,
    Gt,
    Ge,
    Lt,
    Le,
    And,
    Or,
    Xor,
}

impl Op {
    /// Binding strength (higher binds tighter).
    pub(super) fn precedence(self) -> u8 {
        match self {
            Op::Pow => 6,
            Op::Mul | Op::Div | Op::Mod => 5,
            Op::Add | Op::Sub => 4,
            Op::Eq | Op::Ne | Op::Gt | Op::Ge | Op::Lt | Op::Le => 3,
            Op::And | Op::Or | Op::Xor => 2,
        }
    }

    /// The operator spelled by `word` (upper case), for the alphabetic ones.
    pub(super) fn from_word(word: &str) -> Option<Op> {
        Some(match word {
            "MOD" => Op::Mod,
            "EQ" => Op::Eq,
            "NE" => Op::Ne,
            "GT" => Op::Gt,
            "GE" => Op::Ge,
            "LT" => Op::Lt,
            "LE" => Op::Le,
            "AND" => Op::And,
            "OR" => Op::Or,
            "XOR" => Op::Xor,
            _ => return None,
        })
    }
}

impl Func {
    /// The function named `word` (upper case).
    pub(super) fn from_word(word: &str) -> Option<Func> {
        Some(match word {
            "ABS" => Func::Abs,
            "ACOS" => Func::Acos,
            "ASIN" => Func::Asin,
            "COS" => Func::Cos,
            "EXP" => Func::Exp,
            "FIX" => Func::Fix,
            "FUP" => Func::Fup,
            "LN" => Func::Ln,
            "ROUND" => Func::Round,
            "SIN" => Func::Sin,
            "SQRT" => Func::Sqrt,
            "TAN" => Func::Tan,
            _ => return None,
        })
    }
}

/// Why an expression has no value.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum EvalError {
    /// Reading a named parameter that was never set.
    Undefined(String),
    /// A parameter number outside 1..=[`MAX_PARAMETER`] (or not an integer).
    BadParameter(f64),
    /// Division (or MOD) by zero.
    DivisionByZero,
    /// A function outside its domain (`SQRT` of a negative, `LN` of a non-positive, …).
    Domain(&'static str, f64),
    /// The result is not finite.
    NotFinite,
}

impl EvalError {
    /// Message and hint.
    pub(super) fn describe(&self) -> (String, String) {
        match self {
            // LinuxCNC's `#<_hal[pin]>` and `#<_ini[section]name>` read the running
            // machine's HAL pins and INI file ("G-code overview: HAL pins and INI values").
            EvalError::Undefined(n) if n.starts_with("_hal[") => (
                format!("#<{n}> reads a HAL pin of a running LinuxCNC, which the reader does not have"),
                format!("replace #<{n}> by the value the pin has, e.g. a number or #<_my_value> set at the top"),
            ),
            EvalError::Undefined(n) if n.starts_with("_ini[") => (
                format!("#<{n}> reads LinuxCNC's INI file, which the reader does not have"),
                format!("replace #<{n}> by the value of the INI entry"),
            ),
            EvalError::Undefined(n) => (
                format!("the named parameter #<{n}> is read before it is set"),
                format!("set it first, e.g. #<{n}> = 0"),
            ),
            EvalError::BadParameter(v) => (
                format!("parameter number {v} is not an integer in 1..{MAX_PARAMETER}"),
                "numbered parameters are #1 … #5602".to_string(),
            ),
            EvalError::DivisionByZero => (
                "division by zero".to_string(),
                "check the divisor of / or MOD".to_string(),
            ),
            EvalError::Domain(f, v) => (
                format!("{f}[{v}] is outside the function's domain"),
                "check the argument".to_string(),
            ),
            EvalError::NotFinite => (
                "the expression has no finite value".to_string(),
                "check the numbers".to_string(),
            ),
        }
    }
}

/// LinuxCNC's read-only named parameters (`lookup_named_param` and `init_named_parameters`
/// in interp_namedparams.cc; "G-code overview: predefined named parameters"), in the order of
/// [`Params::predefined`]. The first four belong to the O-word runner, the others to the
/// modal state.
pub(super) const PREDEFINED: [&str; N_PREDEFINED] = [
    "_line",
    "_value",
    "_value_returned",
    "_call_level",
    "_remap_level",
    "_task",
    "_vmajor",
    "_vminor",
    "_metric_machine",
    "_motion_mode",
    "_plane",
    "_ccomp",
    "_metric",
    "_imperial",
    "_absolute",
    "_incremental",
    "_inverse_time",
    "_units_per_minute",
    "_units_per_rev",
    "_coord_system",
    "_tool_offset",
    "_retract_r_plane",
    "_retract_old_z",
    "_spindle_rpm_mode",
    "_spindle_css_mode",
    "_ijk_absolute_mode",
    "_lathe_diameter_mode",
    "_lathe_radius_mode",
    "_spindle_on",
    "_spindle_cw",
    "_mist",
    "_flood",
    "_speed_override",
    "_feed_override",
    "_adaptive_feed",
    "_feed_hold",
    "_feed",
    "_rpm",
    "_current_tool",
    "_current_pocket",
    "_selected_pocket",
    "_selected_tool",
    "_x",
    "_y",
    "_z",
    "_a",
    "_b",
    "_c",
    "_u",
    "_v",
    "_w",
    "_abs_x",
    "_abs_y",
    "_abs_z",
    "_abs_a",
    "_abs_b",
    "_abs_c",
    "_abs_u",
    "_abs_v",
    "_abs_w",
];

/// Number of [`PREDEFINED`] parameters.
pub(super) const N_PREDEFINED: usize = 60;

/// Index of `_line` … `_call_level` in [`PREDEFINED`] (kept by the O-word runner).
pub(super) const P_LINE: usize = 0;
pub(super) const P_VALUE: usize = 1;
pub(super) const P_VALUE_RETURNED: usize = 2;
pub(super) const P_CALL_LEVEL: usize = 3;

/// Numbered parameters the reader keeps from its state (LinuxCNC's "numbered parameters"
/// table): G28 and G30 positions (5161–5169, 5181–5189), G92 (5210–5219), the active
/// coordinate system and the work offsets (5220–5390), the tool (5400–5413) and the
/// position (5420–5428). A program reads them; it cannot set them.
pub(super) fn is_system_parameter(i: usize) -> bool {
    matches!(i, 5161..=5169 | 5181..=5189 | 5210..=5390 | 5400..=5413 | 5420..=5428)
}

/// The parameters of a program: numbered, named globals (`#<_x>`), the named locals of
/// the running subroutine (or of the main program) and the read-only predefined ones.
#[derive(Debug, Clone)]
pub(super) struct Params {
    pub(super) numbered: Vec<f64>,
    pub(super) globals: HashMap<String, f64>,
    pub(super) locals: Vec<HashMap<String, f64>>,
    /// Values of the [`PREDEFINED`] parameters, refreshed before each line.
    pub(super) predefined: [f64; N_PREDEFINED],
}

impl Default for Params {
    fn default() -> Self {
        Params {
            numbered: vec![0.0; MAX_PARAMETER + 1],
            globals: HashMap::new(),
            locals: vec![HashMap::new()],
            predefined: [0.0; N_PREDEFINED],
        }
    }
}

impl Params {
    /// Index of numbered parameter `v`.
    pub(super) fn index(v: f64) -> Result<usize, EvalError> {
        let r = v.round();
        if (v - r).abs() > 1e-6 || r < 1.0 || r > MAX_PARAMETER as f64 {
            return Err(EvalError::BadParameter(v));
        }
        Ok(r as usize)
    }

    /// The index of `name` in [`PREDEFINED`].
    pub(super) fn predefined_index(name: &str) -> Option<usize> {
        if !name.starts_with('_') {
            return None;
        }
        PREDEFINED.iter().position(|p| *p == name)
    }

    pub(super) fn named(&self, name: &str) -> Option<f64> {
        if let Some(i) = Self::predefined_index(name) {
            return Some(self.predefined[i]);
        }
        if name.starts_with('_') {
            self.globals.get(name).copied()
        } else {
            self.locals.last().and_then(|m| m.get(name)).copied()
        }
    }

    pub(super) fn set_named(&mut self, name: &str, v: f64) {
        if name.starts_with('_') {
            self.globals.insert(name.to_string(), v);
        } else if let Some(m) = self.locals.last_mut() {
            m.insert(name.to_string(), v);
        }
    }

    /// Evaluates `e` with the current values.
    pub(super) fn eval(&self, e: &Expr) -> Result<f64, EvalError> {
        let v = match e {
            Expr::Num(v) => *v,
            Expr::Param(i) => self.numbered[Self::index(self.eval(i)?)?],
            Expr::Named(n) => self
                .named(n)
                .ok_or_else(|| EvalError::Undefined(n.clone()))?,
            Expr::Exists(n) => f64::from(u8::from(self.named(n).is_some())),
            Expr::Neg(a) => -self.eval(a)?,
            Expr::Func(f, a) => func(*f, self.eval(a)?)?,
            Expr::Atan(a, b) => self.eval(a)?.atan2(self.eval(b)?).to_degrees(),
            Expr::Bin(op, a, b) => binary(*op, self.eval(a)?, self.eval(b)?)?,
        };
        if v.is_finite() {
            Ok(v)
        } else {
            Err(EvalError::NotFinite)
        }
    }
}

/// A unary function of the dialect (degrees for the trigonometric ones).
fn func(f: Func, x: f64) -> Result<f64, EvalError> {
    Ok(match f {
        Func::Abs => x.abs(),
        Func::Acos if (-1.0..=1.0).contains(&x) => x.acos().to_degrees(),
        Func::Asin if (-1.0..=1.0).contains(&x) => x.asin().to_degrees(),
        Func::Acos => return Err(EvalError::Domain("ACOS", x)),
        Func::Asin => return Err(EvalError::Domain("ASIN", x)),
        Func::Cos => x.to_radians().cos(),
        Func::Exp => x.exp(),
        Func::Fix => x.floor(),
        Func::Fup => x.ceil(),
        Func::Ln if x > 0.0 => x.ln(),
        Func::Ln => return Err(EvalError::Domain("LN", x)),
        Func::Round => x.round(),
        Func::Sin => x.to_radians().sin(),
        Func::Sqrt if x >= 0.0 => x.sqrt(),
        Func::Sqrt => return Err(EvalError::Domain("SQRT", x)),
        Func::Tan => x.to_radians().tan(),
    })
}

/// A binary operation; comparisons and logic give 1.0 or 0.0 (LinuxCNC: a value is true when
/// it is not 0).
fn binary(op: Op, a: f64, b: f64) -> Result<f64, EvalError> {
    let t = |c: bool| f64::from(u8::from(c));
    // LinuxCNC compares with a tolerance of 1e-6 (TOLERANCE_EQUAL).
    let eq = (a - b).abs() < 1e-6;
    Ok(match op {
        Op::Pow => a.powf(b),
        Op::Mul => a * b,
        Op::Div if b == 0.0 => return Err(EvalError::DivisionByZero),
        Op::Div => a / b,
        Op::Mod if b == 0.0 => return Err(EvalError::DivisionByZero),
        // LinuxCNC: the result has the sign of the divisor's absolute value (always >= 0
        // for a positive divisor).
        Op::Mod => {
            let r = a % b;
            if r < 0.0 {
                r + b.abs()
            } else {
                r
            }
        }
        Op::Add => a + b,
        Op::Sub => a - b,
        Op::Eq => t(eq),
        Op::Ne => t(!eq),
        Op::Gt => t(a > b),
        Op::Ge => t(a >= b),
        Op::Lt => t(a < b),
        Op::Le => t(a <= b),
        Op::And => t(a != 0.0 && b != 0.0),
        Op::Or => t(a != 0.0 || b != 0.0),
        Op::Xor => t((a != 0.0) != (b != 0.0)),
    })
}
