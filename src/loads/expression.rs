//! Expressions of x, y, z, t: parsed and checked once, evaluated many times.
//!
//! ## The crates we measured, and why we now evaluate ourselves
//!
//! Candidates on crates.io, timed with `-20*t*y/sqrt(x^2+y^2)` and `800*t` compiled once and
//! evaluated at 2·10⁶ points (release build, best of 5, the shared 2-core machine with other
//! builds running, so ±20 %); a hand-written Rust closure takes 4.5 ns and 4.0 ns.
//!
//! | crate | version | ns/eval | ns/eval `800*t` | maintained | fit |
//! |---|---|---|---|---|---|
//! | exmex | 0.21.0 | 98 | 28 | yes: 21 minor releases, the latest built on current dependencies (rand 0.10, toml 1.1); MIT OR Apache-2.0 | all functions; values on the stack (no allocation) up to 32 nodes; `Send + Sync` |
//! | mathexpr | 0.1.1 | 73 | 19 | young (two 0.1 releases, one author); MIT | a `Vec` allocated per evaluation; `x/0` is an error, not ±∞; math through `libm` |
//! | fasteval | 0.2.4 | 122 | 9 | no: last release January 2020 | no `sqrt` (a named callback per evaluation), `log` is base 10, `pi()` |
//! | meval | 0.2.0 | 136 | 41 | no: last release 2018; its `nom` 1 is flagged for future rejection by rustc | — |
//! | evalexpr | 13.1.0 | 900 | 310 | yes, but AGPL-3.0-only since 12 (we are MIT OR Apache-2.0) | functions are `math::sqrt`, … |
//!
//! exmex was chosen first, and evaluated the canonical text our own grammar (below) wrote for it:
//! 55 ns and 27 ns through [`Expression`]. Two costs of it grew faster than the formula
//! (issue 26): its flat evaluator finds each operator's operands by scanning a bitset of the
//! ones already used, so one evaluation is O(n²) in the number n of operators (dev build,
//! `x+x+…+x`: 8.2 µs for 512 terms, 29 µs for 1024, 84 µs for 2000; a body force near the
//! 4096-byte limit cost 8 s per step on a 32k-triangle mesh), and its symbolic `partial` of
//! a product of n factors has n² of them (and it could not differentiate `abs`, `min`, `max`,
//! `atan2`). The grammar was already ours, so the evaluator now is too: the syntax tree is
//! compiled once to a postfix program for a small stack machine, evaluated in time linear in
//! its length, with the values on the stack (no allocation) up to a stack depth of 32;
//! derivatives are forward-mode automatic differentiation over the same program (dual
//! numbers), linear as well. Figures: `cargo run --release --example expression_bench`
//! (its scaling table: the cost per term stays flat from 64 to 2000 terms).
//!
//! The arithmetic is exactly exmex's, operation for operation, so values are bit-identical to
//! the ones exmex gave: `+ - * /` of f64 left to right, `^` is `powf` except that the square of
//! a variable `x^2` is the product x·x (as exact: both are x² correctly rounded), unary minus
//! is negation, `log` and `ln` are `f64::ln`, `min`, `max`, `atan2` are f64's, and a subtree
//! without variables is folded at compile time with the same operations.
//!
//! ## Why our own grammar
//!
//! exmex (and mathexpr) bind unary minus tighter than `^`: `-x^2` is (−x)², so `exp(-x^2)`
//! would silently be exp(x²). exmex also reads `2^3^2` as (2³)², takes any unknown name for a
//! variable, and has no exponent in number literals (`1e-3`). So [`Expression::parse`] parses the
//! text itself with the usual precedence (the one of MOOSE's ParsedFunction and of Python) and
//! names unknown variables and functions.
//!
//! ## Grammar
//!
//! ```text
//! expr    = term   { ("+" | "-") term }
//! term    = unary  { ("*" | "/") unary }
//! unary   = ("-" | "+") unary | power
//! power   = primary [ ("^" | "**") unary ]        right-associative: 2^3^2 = 2^9
//! primary = number | variable | constant | function "(" expr { "," expr } ")" | "(" expr ")"
//! ```
//!
//! Variables `x y z t`; constants `pi`, `e`; functions `sin cos tan asin acos atan sinh cosh
//! tanh exp log ln log10 sqrt abs` (one argument; `log` is the natural logarithm, as in
//! ParsedFunction and FEniCS) and `min max atan2` (two). So `-x^2` = −(x²) and `2^-1` = ½.
//!
//! ## Derivatives
//!
//! [`Expression::derivative`] carries (value, ∂/∂v) pairs through the program: the usual rules,
//! `a^b` as b·a^(b−1)·a′ + a^b·ln(a)·b′ with the first term left out where a′ = 0 and the
//! second where b′ = 0 (so a negative base with a constant exponent has its derivative),
//! `abs` as sign(a)·a′ with the right derivative a′ at a = 0 (a law's slip rate is r ≥ 0, so
//! `abs(r)` then has the slope of r), `min` and `max` the derivative of the argument they
//! return (of the first on a tie), `atan2(a, b)` as (b a′ − a b′)/(a² + b²). A part of the
//! expression that does not depend on v has derivative exactly 0, even where its value is
//! infinite or NaN (`sqrt(x)*r` at x = 0 has the r-derivative 0, not NaN).

use std::fmt;
use std::sync::Arc;

/// Every variable an expression may use: the point (x, y, z) and t, which every expression
/// may use, then the arguments of the laws on Γ_C, which only the laws allow
/// ([`Expression::parse_with`]): the slip rate r and the temperature θ (`theta`).
const VARIABLES: [&str; 6] = ["x", "y", "z", "t", "r", "theta"];

/// The number of variables every expression may use (x, y, z, t).
const SPACE_TIME: usize = 4;

/// The functions of the grammar: name, instruction, number of arguments.
const FUNCTIONS: [(&str, Op, usize); 18] = [
    ("sin", Op::Sin, 1),
    ("cos", Op::Cos, 1),
    ("tan", Op::Tan, 1),
    ("asin", Op::Asin, 1),
    ("acos", Op::Acos, 1),
    ("atan", Op::Atan, 1),
    ("sinh", Op::Sinh, 1),
    ("cosh", Op::Cosh, 1),
    ("tanh", Op::Tanh, 1),
    ("exp", Op::Exp, 1),
    ("log", Op::Ln, 1),
    ("ln", Op::Ln, 1),
    ("log10", Op::Log10, 1),
    ("sqrt", Op::Sqrt, 1),
    ("abs", Op::Abs, 1),
    ("min", Op::Min, 2),
    ("max", Op::Max, 2),
    ("atan2", Op::Atan2, 2),
];

/// Named constants, replaced by their values at parse time.
const CONSTANTS: [(&str, f64); 2] = [("pi", std::f64::consts::PI), ("e", std::f64::consts::E)];

/// The longest expression text, in bytes: a datum or a law is a formula, not data (a longer
/// text would build a syntax tree too deep for the stack).
pub const MAX_EXPRESSION_BYTES: usize = 4096;

/// The deepest nesting of parentheses, signs and powers in an expression.
pub const MAX_EXPRESSION_DEPTH: usize = 100;

/// Errors of [`Expression::parse`]; each names the text it is about.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExpressionError {
    /// The text is not an expression of the grammar.
    #[error("cannot parse the expression `{text}`: {message}")]
    Parse { text: String, message: String },
    /// A name that is neither a variable nor a constant.
    #[error(
        "unknown variable `{name}` in the expression `{text}` (the variables are {allowed}; the constants pi and e)"
    )]
    UnknownVariable {
        text: String,
        name: String,
        allowed: String,
    },
    /// A name called as a function that is not one.
    #[error("unknown function `{name}` in the expression `{text}` (the functions are sin, cos, tan, asin, acos, atan, sinh, cosh, tanh, exp, log, ln, log10, sqrt, abs, min, max, atan2)")]
    UnknownFunction { text: String, name: String },
    /// A text longer than [`MAX_EXPRESSION_BYTES`] or nested deeper than
    /// [`MAX_EXPRESSION_DEPTH`].
    #[error("the expression `{start}…` is {what} (at most {limit}); write a shorter formula")]
    TooLarge {
        start: String,
        what: &'static str,
        limit: usize,
    },
    /// A known function called with the wrong number of arguments.
    #[error("`{name}` takes {expected} argument(s) but is given {found} in the expression `{text}`")]
    Arity {
        text: String,
        name: String,
        expected: usize,
        found: usize,
    },
}

/// A scalar expression of x, y, z (the point) and t (the time).
///
/// ```
/// use thermocontact::loads::Expression;
/// let f = Expression::parse("-20*t*y/sqrt(x^2 + y^2)").unwrap();
/// assert_eq!(f.eval([3.0, 4.0, 0.0], 0.5), -8.0);
/// assert!(f.uses_space() && f.uses_time());
/// // The usual precedence: −(x²), not (−x)².
/// let g = Expression::parse("exp(-x^2)").unwrap();
/// assert!((g.eval([2.0, 0.0, 0.0], 0.0) - (-4.0f64).exp()).abs() < 1e-15);
/// ```
#[derive(Clone)]
pub struct Expression {
    text: String,
    body: Body,
    /// Which of [`VARIABLES`] occur.
    uses: [bool; 6],
}

#[derive(Clone)]
enum Body {
    /// No variable occurs: evaluated once at parse time.
    Constant(f64),
    /// The compiled program; `tangent` is `Some(k)` for the derivative in `VARIABLES[k]`.
    Program {
        program: Arc<Program>,
        tangent: Option<usize>,
    },
}

impl Expression {
    /// Parses `text`, an expression of x, y, z and t; checks every name, and compiles it once.
    pub fn parse(text: &str) -> Result<Expression, ExpressionError> {
        Self::parse_with(text, &[])
    }

    /// Parses `text`, an expression of x, y, z, t and the further variables `extra` (each `r`,
    /// the slip rate, or `theta`, the temperature: the arguments of a law on Γ_C).
    pub fn parse_with(text: &str, extra: &[&str]) -> Result<Expression, ExpressionError> {
        if text.len() > MAX_EXPRESSION_BYTES {
            return Err(too_large(text, "longer than its byte limit", MAX_EXPRESSION_BYTES));
        }
        let mut allowed = [false; VARIABLES.len()];
        allowed[..SPACE_TIME].fill(true);
        for name in extra {
            let k = VARIABLES
                .iter()
                .position(|v| v == name)
                .expect("a variable of VARIABLES");
            allowed[k] = true;
        }
        let node = Parser::new(text, allowed)?.parse()?;
        let mut uses = [false; VARIABLES.len()];
        node.mark_variables(&mut uses);
        let body = if uses.iter().any(|&u| u) {
            Body::Program {
                program: Arc::new(Program::compile(&node)),
                tangent: None,
            }
        } else {
            Body::Constant(node.value())
        };
        Ok(Expression {
            text: text.to_string(),
            body,
            uses,
        })
    }

    /// The partial derivative with respect to `variable` (one of x, y, z, t, r, theta), by
    /// forward-mode automatic differentiation (see the module's documentation for the rules
    /// at the kinks of `abs`, `min`, `max`); 0 if the expression does not use `variable`. The
    /// derivative takes the same arguments as the expression and costs about twice as much to
    /// evaluate.
    ///
    /// # Panics
    ///
    /// If `variable` is none of x, y, z, t, r, theta, or for the derivative of a derivative in a
    /// variable it uses (second derivatives are not implemented).
    pub fn derivative(&self, variable: &str) -> Expression {
        let k = VARIABLES
            .iter()
            .position(|v| *v == variable)
            .unwrap_or_else(|| panic!("`{variable}` is not one of the variables {VARIABLES:?}"));
        let body = match &self.body {
            Body::Program { program, tangent } if self.uses[k] => {
                assert!(
                    tangent.is_none(),
                    "second derivatives are not implemented ({})",
                    self.text
                );
                Body::Program {
                    program: Arc::clone(program),
                    tangent: Some(k),
                }
            }
            _ => Body::Constant(0.0),
        };
        Expression {
            text: format!("d/d{variable} ({})", self.text),
            body,
            uses: self.uses,
        }
    }

    /// The value at the point `x` and time `t`. IEEE semantics: `1/0` is +∞, `sqrt(-1)` is NaN
    /// (the loads check for non-finite values).
    #[inline]
    pub fn eval(&self, x: [f64; 3], t: f64) -> f64 {
        self.eval_with(x, t, [0.0; 2])
    }

    /// The value at the point `x`, time `t` and `laws` = (r, θ): the slip rate and the
    /// temperature, for an expression parsed by [`Expression::parse_with`].
    #[inline]
    pub fn eval_with(&self, x: [f64; 3], t: f64, laws: [f64; 2]) -> f64 {
        let variables = [x[0], x[1], x[2], t, laws[0], laws[1]];
        match &self.body {
            Body::Constant(value) => *value,
            Body::Program { program, tangent: None } => program.value(&variables),
            Body::Program {
                program,
                tangent: Some(k),
            } => program.derivative(&variables, *k),
        }
    }

    /// Whether `variable` (one of x, y, z, t, r, theta) occurs.
    pub fn uses(&self, variable: &str) -> bool {
        VARIABLES
            .iter()
            .position(|v| *v == variable)
            .is_some_and(|k| self.uses[k])
    }

    /// Whether any of x, y, z occurs.
    pub fn uses_space(&self) -> bool {
        self.uses[..3].iter().any(|&u| u)
    }

    /// Whether t occurs.
    pub fn uses_time(&self) -> bool {
        self.uses[3]
    }

    /// The text as given.
    pub fn text(&self) -> &str {
        &self.text
    }
}

impl fmt::Debug for Expression {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_tuple("Expression").field(&self.text).finish()
    }
}

impl PartialEq for Expression {
    /// Two expressions are equal when their texts are.
    fn eq(&self, other: &Self) -> bool {
        self.text == other.text
    }
}

/// The syntax tree of the grammar.
///
/// A sum or a product is one [`Node::Chain`], however many terms it has, so the tree is only as
/// deep as the nesting: a level of [`MAX_EXPRESSION_DEPTH`] (a parenthesis, a sign, a power, a
/// function's argument) adds at most four nodes (a `Negate`, or a `Power` or `Call`, then the
/// chains of its operand's `+` and `*`), and the tree is at most 4·(MAX_EXPRESSION_DEPTH + 1)
/// = 404 nodes deep, which bounds every recursion over it.
#[derive(Debug)]
enum Node {
    Number(f64),
    Variable(usize),
    Negate(Box<Node>),
    /// `first op₁ n₁ op₂ n₂ …`, the operators all `+`/`-` or all `*`/`/`, evaluated from the
    /// left: ((first op₁ n₁) op₂ n₂) …, as a left-associative binary tree would be.
    Chain(Box<Node>, Vec<(char, Node)>),
    /// base ^ exponent.
    Power(Box<Node>, Box<Node>),
    /// Index into [`FUNCTIONS`] and the arguments.
    Call(usize, Vec<Node>),
}

impl Node {
    fn mark_variables(&self, uses: &mut [bool; VARIABLES.len()]) {
        match self {
            Node::Number(_) => {}
            Node::Variable(k) => uses[*k] = true,
            Node::Negate(a) => a.mark_variables(uses),
            Node::Chain(first, rest) => {
                first.mark_variables(uses);
                rest.iter().for_each(|(_, a)| a.mark_variables(uses));
            }
            Node::Power(a, b) => {
                a.mark_variables(uses);
                b.mark_variables(uses);
            }
            Node::Call(_, args) => args.iter().for_each(|a| a.mark_variables(uses)),
        }
    }

    /// Whether the square of a variable, `x^2`, which is evaluated as the product x·x (as
    /// exact as `powf`: both are x² correctly rounded, and faster).
    fn is_square_of_variable(base: &Node, exponent: &Node) -> bool {
        matches!(base, Node::Variable(_)) && matches!(exponent, Node::Number(v) if *v == 2.0)
    }

    /// Appends the postfix instructions of the tree to `ops`, one per number, variable,
    /// operator and function (none for parentheses), so the program is never longer than the
    /// text has tokens.
    fn compile(&self, ops: &mut Vec<Op>) {
        match self {
            Node::Number(v) => ops.push(Op::Const(*v)),
            Node::Variable(k) => ops.push(Op::Var(*k)),
            Node::Negate(a) => {
                a.compile(ops);
                emit(ops, Op::Neg);
            }
            Node::Chain(first, rest) => {
                first.compile(ops);
                for (op, a) in rest {
                    a.compile(ops);
                    emit(ops, Op::of_symbol(*op));
                }
            }
            Node::Power(a, b) if Node::is_square_of_variable(a, b) => {
                a.compile(ops);
                ops.push(Op::Square);
            }
            Node::Power(a, b) => {
                a.compile(ops);
                b.compile(ops);
                emit(ops, Op::Pow);
            }
            Node::Call(f, args) => {
                args.iter().for_each(|a| a.compile(ops));
                emit(ops, FUNCTIONS[*f].1);
            }
        }
    }

    /// The value of a tree without variables, with the program's arithmetic.
    fn value(&self) -> f64 {
        match self {
            Node::Number(v) => *v,
            Node::Variable(_) => unreachable!("only called on constant trees"),
            Node::Negate(a) => Op::Neg.unary(a.value()),
            Node::Chain(first, rest) => rest
                .iter()
                .fold(first.value(), |a, (op, b)| Op::of_symbol(*op).binary(a, b.value())),
            Node::Power(a, b) => Op::Pow.binary(a.value(), b.value()),
            Node::Call(f, args) => match args.as_slice() {
                [a] => FUNCTIONS[*f].1.unary(a.value()),
                [a, b] => FUNCTIONS[*f].1.binary(a.value(), b.value()),
                _ => unreachable!("arity checked by the parser"),
            },
        }
    }
}

/// Appends `op` to the program, folding it when its operands are constants (the same
/// operation on the same values as at evaluation, so the same bits).
fn emit(ops: &mut Vec<Op>, op: Op) {
    match (op.arity(), ops.as_slice()) {
        (1, [.., Op::Const(a)]) => {
            let value = op.unary(*a);
            ops.pop();
            ops.push(Op::Const(value));
        }
        (2, [.., Op::Const(a), Op::Const(b)]) => {
            let value = op.binary(*a, *b);
            ops.truncate(ops.len() - 2);
            ops.push(Op::Const(value));
        }
        _ => ops.push(op),
    }
}

/// One instruction of the stack machine.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Op {
    /// Pushes a number.
    Const(f64),
    /// Pushes the value of `VARIABLES[k]`.
    Var(usize),
    /// a·a of the top (the square of a variable).
    Square,
    Neg,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Exp,
    Ln,
    Log10,
    Sqrt,
    Abs,
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    Min,
    Max,
    Atan2,
}

impl Op {
    /// The operator of a chain.
    fn of_symbol(symbol: char) -> Op {
        match symbol {
            '+' => Op::Add,
            '-' => Op::Sub,
            '*' => Op::Mul,
            '/' => Op::Div,
            other => unreachable!("`{other}` is not a chain's operator"),
        }
    }

    /// How many values it pops (0 for the pushes).
    fn arity(self) -> usize {
        match self {
            Op::Const(_) | Op::Var(_) => 0,
            Op::Add | Op::Sub | Op::Mul | Op::Div | Op::Pow | Op::Min | Op::Max | Op::Atan2 => 2,
            _ => 1,
        }
    }

    /// The value of a one-argument instruction.
    #[inline(always)]
    fn unary(self, a: f64) -> f64 {
        match self {
            Op::Square => a * a,
            Op::Neg => -a,
            Op::Sin => a.sin(),
            Op::Cos => a.cos(),
            Op::Tan => a.tan(),
            Op::Asin => a.asin(),
            Op::Acos => a.acos(),
            Op::Atan => a.atan(),
            Op::Sinh => a.sinh(),
            Op::Cosh => a.cosh(),
            Op::Tanh => a.tanh(),
            Op::Exp => a.exp(),
            Op::Ln => a.ln(),
            Op::Log10 => a.log10(),
            Op::Sqrt => a.sqrt(),
            Op::Abs => a.abs(),
            _ => unreachable!("{self:?} is not a one-argument instruction"),
        }
    }

    /// The value of a two-argument instruction.
    #[inline(always)]
    fn binary(self, a: f64, b: f64) -> f64 {
        match self {
            Op::Add => a + b,
            Op::Sub => a - b,
            Op::Mul => a * b,
            Op::Div => a / b,
            Op::Pow => a.powf(b),
            Op::Min => a.min(b),
            Op::Max => a.max(b),
            Op::Atan2 => a.atan2(b),
            _ => unreachable!("{self:?} is not a two-argument instruction"),
        }
    }

    /// The derivative of a one-argument instruction: `a` the argument, `da` its derivative,
    /// `value` the instruction's value. Only called with `da` ≠ 0.
    #[inline(always)]
    fn unary_derivative(self, a: f64, da: f64, value: f64) -> f64 {
        let slope = match self {
            Op::Square => 2.0 * a,
            Op::Neg => -1.0,
            Op::Sin => a.cos(),
            Op::Cos => -a.sin(),
            Op::Tan => 1.0 + value * value,
            Op::Asin => 1.0 / (1.0 - a * a).sqrt(),
            Op::Acos => -1.0 / (1.0 - a * a).sqrt(),
            Op::Atan => 1.0 / (1.0 + a * a),
            Op::Sinh => a.cosh(),
            Op::Cosh => a.sinh(),
            Op::Tanh => 1.0 - value * value,
            Op::Exp => value,
            Op::Ln => 1.0 / a,
            Op::Log10 => 1.0 / (a * std::f64::consts::LN_10),
            Op::Sqrt => 0.5 / value,
            // sign(a), +1 at the kink: the right derivative, the one a law has on its domain
            // r ≥ 0 (NaN stays NaN).
            Op::Abs if a == 0.0 => 1.0,
            Op::Abs => a.signum(),
            _ => unreachable!("{self:?} is not a one-argument instruction"),
        };
        slope * da
    }

    /// The derivative of a two-argument instruction of value `value`, not both `da` and `db`
    /// zero. A zero derivative's term is left out (0·∞ would be NaN).
    #[inline(always)]
    fn binary_derivative(self, (a, da): (f64, f64), (b, db): (f64, f64), value: f64) -> f64 {
        let times = |d: f64, factor: f64| if d == 0.0 { 0.0 } else { d * factor };
        match self {
            Op::Add => da + db,
            Op::Sub => da - db,
            Op::Mul => times(da, b) + times(db, a),
            Op::Div => (da - times(db, value)) / b,
            Op::Pow => {
                let base = if da == 0.0 { 0.0 } else { b * a.powf(b - 1.0) * da };
                let exponent = if db == 0.0 { 0.0 } else { value * a.ln() * db };
                base + exponent
            }
            // The derivative of the argument returned: f64::min and max return the other
            // one when an argument is NaN, and the first on a tie.
            Op::Min => {
                if b < a || a.is_nan() {
                    db
                } else {
                    da
                }
            }
            Op::Max => {
                if b > a || a.is_nan() {
                    db
                } else {
                    da
                }
            }
            Op::Atan2 => (times(da, b) - times(db, a)) / (a * a + b * b),
            _ => unreachable!("{self:?} is not a two-argument instruction"),
        }
    }
}

/// The postfix program of an expression and the deepest stack it needs.
#[derive(Debug)]
struct Program {
    ops: Vec<Op>,
    stack: usize,
}

impl Program {
    fn compile(node: &Node) -> Program {
        let mut ops = Vec::new();
        node.compile(&mut ops);
        let (mut depth, mut stack) = (0usize, 0usize);
        for op in &ops {
            depth = depth + 1 - op.arity();
            stack = stack.max(depth);
        }
        debug_assert_eq!(depth, 1, "a program leaves one value");
        Program { ops, stack }
    }

    /// The value at `variables` (in the order of [`VARIABLES`]).
    #[inline]
    fn value(&self, variables: &[f64; VARIABLES.len()]) -> f64 {
        if self.stack <= 8 {
            self.run(&mut [0.0; 8], variables)
        } else if self.stack <= 32 {
            self.run(&mut [0.0; 32], variables)
        } else {
            self.run(&mut vec![0.0; self.stack], variables)
        }
    }

    fn run(&self, stack: &mut [f64], variables: &[f64; VARIABLES.len()]) -> f64 {
        // `n` values on the stack; the compiler guarantees every pop has its operands.
        let mut n = 0;
        for &op in &self.ops {
            match op {
                Op::Const(v) => {
                    stack[n] = v;
                    n += 1;
                }
                Op::Var(k) => {
                    stack[n] = variables[k];
                    n += 1;
                }
                // The frequent instructions spelled out, the others through `Op::binary` and
                // `Op::unary` (the same arithmetic).
                Op::Add => {
                    n -= 1;
                    stack[n - 1] += stack[n];
                }
                Op::Sub => {
                    n -= 1;
                    stack[n - 1] -= stack[n];
                }
                Op::Mul => {
                    n -= 1;
                    stack[n - 1] *= stack[n];
                }
                Op::Div => {
                    n -= 1;
                    stack[n - 1] /= stack[n];
                }
                Op::Square => stack[n - 1] *= stack[n - 1],
                Op::Neg => stack[n - 1] = -stack[n - 1],
                Op::Pow | Op::Min | Op::Max | Op::Atan2 => {
                    n -= 1;
                    stack[n - 1] = op.binary(stack[n - 1], stack[n]);
                }
                _ => stack[n - 1] = op.unary(stack[n - 1]),
            }
        }
        stack[0]
    }

    /// The derivative in `VARIABLES[tangent]` at `variables`: the program on (value,
    /// derivative) pairs.
    fn derivative(&self, variables: &[f64; VARIABLES.len()], tangent: usize) -> f64 {
        if self.stack <= 8 {
            self.run_dual(&mut [(0.0, 0.0); 8], variables, tangent)
        } else if self.stack <= 32 {
            self.run_dual(&mut [(0.0, 0.0); 32], variables, tangent)
        } else {
            self.run_dual(&mut vec![(0.0, 0.0); self.stack], variables, tangent)
        }
    }

    fn run_dual(&self, stack: &mut [(f64, f64)], variables: &[f64; VARIABLES.len()], tangent: usize) -> f64 {
        let mut n = 0;
        for &op in &self.ops {
            match op {
                Op::Const(v) => {
                    stack[n] = (v, 0.0);
                    n += 1;
                }
                Op::Var(k) => {
                    stack[n] = (variables[k], if k == tangent { 1.0 } else { 0.0 });
                    n += 1;
                }
                Op::Add | Op::Sub | Op::Mul | Op::Div | Op::Pow | Op::Min | Op::Max | Op::Atan2 => {
                    n -= 1;
                    let (a, b) = (stack[n - 1], stack[n]);
                    let value = op.binary(a.0, b.0);
                    let derivative = if a.1 == 0.0 && b.1 == 0.0 {
                        0.0
                    } else {
                        op.binary_derivative(a, b, value)
                    };
                    stack[n - 1] = (value, derivative);
                }
                _ => {
                    let (a, da) = stack[n - 1];
                    let value = op.unary(a);
                    let derivative = if da == 0.0 {
                        0.0
                    } else {
                        op.unary_derivative(a, da, value)
                    };
                    stack[n - 1] = (value, derivative);
                }
            }
        }
        stack[0].1
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Token<'a> {
    Number(f64),
    Name(&'a str),
    /// One of `+ - * / ^ ( ) ,` (`**` is read as `^`).
    Symbol(char),
    End,
}

/// A recursive-descent parser over the tokens of the text.
struct Parser<'a> {
    text: &'a str,
    /// Which of [`VARIABLES`] this expression may use.
    allowed: [bool; VARIABLES.len()],
    /// The nesting depth of the `unary` being parsed (every recursion passes through it).
    depth: usize,
    /// Tokens with the byte offset where each starts.
    tokens: Vec<(Token<'a>, usize)>,
    next: usize,
}

impl<'a> Parser<'a> {
    fn new(text: &'a str, allowed: [bool; VARIABLES.len()]) -> Result<Self, ExpressionError> {
        let bytes = text.as_bytes();
        let mut tokens = Vec::new();
        let mut i = 0;
        while i < bytes.len() {
            let c = bytes[i];
            let start = i;
            if c.is_ascii_whitespace() {
                i += 1;
                continue;
            }
            if c.is_ascii_digit() || c == b'.' {
                let digits = |i: &mut usize| {
                    let from = *i;
                    while *i < bytes.len() && bytes[*i].is_ascii_digit() {
                        *i += 1;
                    }
                    *i > from
                };
                let mut has_digits = digits(&mut i);
                if i < bytes.len() && bytes[i] == b'.' {
                    i += 1;
                    has_digits |= digits(&mut i);
                }
                if !has_digits {
                    return Err(parse_error(text, start, "a lone `.` is not a number"));
                }
                // An exponent only if digits follow: `2e` stays an error below, not 2·e.
                if i < bytes.len() && (bytes[i] == b'e' || bytes[i] == b'E') {
                    let mut j = i + 1;
                    if j < bytes.len() && (bytes[j] == b'+' || bytes[j] == b'-') {
                        j += 1;
                    }
                    if digits(&mut j) {
                        i = j;
                    }
                }
                let value: f64 = text[start..i]
                    .parse()
                    .map_err(|_| parse_error(text, start, "malformed number"))?;
                if !value.is_finite() {
                    return Err(parse_error(text, start, "number out of the range of f64"));
                }
                tokens.push((Token::Number(value), start));
            } else if c.is_ascii_alphabetic() || c == b'_' {
                while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                    i += 1;
                }
                tokens.push((Token::Name(&text[start..i]), start));
            } else if c == b'*' && bytes.get(i + 1) == Some(&b'*') {
                i += 2;
                tokens.push((Token::Symbol('^'), start));
            } else if b"+-*/^(),".contains(&c) {
                i += 1;
                tokens.push((Token::Symbol(c as char), start));
            } else {
                let ch = text[start..].chars().next().expect("not at the end");
                return Err(parse_error(text, start, &format!("unexpected character `{ch}`")));
            }
        }
        tokens.push((Token::End, text.len()));
        Ok(Parser {
            text,
            allowed,
            depth: 0,
            tokens,
            next: 0,
        })
    }

    fn parse(mut self) -> Result<Node, ExpressionError> {
        if self.peek() == Token::End {
            return Err(parse_error(self.text, 0, "the expression is empty"));
        }
        let node = self.expr()?;
        match self.peek() {
            Token::End => Ok(node),
            Token::Symbol(')') => Err(self.error_here("unmatched `)`")),
            _ => Err(self.error_here("expected an operator")),
        }
    }

    fn peek(&self) -> Token<'a> {
        self.tokens[self.next].0
    }

    fn error_here(&self, message: &str) -> ExpressionError {
        parse_error(self.text, self.tokens[self.next].1, message)
    }

    fn expr(&mut self) -> Result<Node, ExpressionError> {
        let first = self.term()?;
        self.chain(first, &['+', '-'], Self::term)
    }

    fn term(&mut self) -> Result<Node, ExpressionError> {
        let first = self.unary()?;
        self.chain(first, &['*', '/'], Self::unary)
    }

    /// `first` and every further `op operand` with `op` one of `ops`: one [`Node::Chain`]
    /// (`first` alone if there is none).
    fn chain(
        &mut self,
        first: Node,
        ops: &[char; 2],
        mut operand: impl FnMut(&mut Self) -> Result<Node, ExpressionError>,
    ) -> Result<Node, ExpressionError> {
        let mut rest = Vec::new();
        while let Token::Symbol(op) = self.peek() {
            if !ops.contains(&op) {
                break;
            }
            self.next += 1;
            rest.push((op, operand(self)?));
        }
        Ok(if rest.is_empty() {
            first
        } else {
            Node::Chain(Box::new(first), rest)
        })
    }

    fn unary(&mut self) -> Result<Node, ExpressionError> {
        self.depth += 1;
        if self.depth > MAX_EXPRESSION_DEPTH {
            return Err(too_large(
                self.text,
                "nested deeper than its limit",
                MAX_EXPRESSION_DEPTH,
            ));
        }
        let node = self.unary_at_depth();
        self.depth -= 1;
        node
    }

    fn unary_at_depth(&mut self) -> Result<Node, ExpressionError> {
        match self.peek() {
            Token::Symbol('-') => {
                self.next += 1;
                Ok(Node::Negate(Box::new(self.unary()?)))
            }
            Token::Symbol('+') => {
                self.next += 1;
                self.unary()
            }
            _ => self.power(),
        }
    }

    fn power(&mut self) -> Result<Node, ExpressionError> {
        let base = self.primary()?;
        if self.peek() == Token::Symbol('^') {
            self.next += 1;
            // The exponent is a `unary`, itself ending in a `power`: right associativity.
            let exponent = self.unary()?;
            return Ok(Node::Power(Box::new(base), Box::new(exponent)));
        }
        Ok(base)
    }

    fn primary(&mut self) -> Result<Node, ExpressionError> {
        let (token, at) = self.tokens[self.next];
        match token {
            Token::Number(v) => {
                self.next += 1;
                Ok(Node::Number(v))
            }
            Token::Symbol('(') => {
                self.next += 1;
                let node = self.expr()?;
                self.expect(')', "expected `)`")?;
                Ok(node)
            }
            Token::Name(name) => {
                self.next += 1;
                let called = self.peek() == Token::Symbol('(');
                if let Some(k) = (VARIABLES.iter().position(|v| *v == name)).filter(|&k| self.allowed[k]) {
                    if called {
                        return Err(parse_error(
                            self.text,
                            at,
                            &format!("`{name}` is a variable, not a function"),
                        ));
                    }
                    return Ok(Node::Variable(k));
                }
                if let Some((_, value)) = CONSTANTS.iter().find(|(c, _)| *c == name) {
                    if called {
                        return Err(parse_error(
                            self.text,
                            at,
                            &format!("`{name}` is a constant, not a function"),
                        ));
                    }
                    return Ok(Node::Number(*value));
                }
                match FUNCTIONS.iter().position(|(f, _, _)| *f == name) {
                    Some(f) if called => self.call(f),
                    Some(_) => Err(parse_error(
                        self.text,
                        at,
                        &format!("the function `{name}` needs its argument in parentheses"),
                    )),
                    None if called => Err(ExpressionError::UnknownFunction {
                        text: self.text.to_string(),
                        name: name.to_string(),
                    }),
                    None => Err(ExpressionError::UnknownVariable {
                        text: self.text.to_string(),
                        name: name.to_string(),
                        allowed: self.allowed_names(),
                    }),
                }
            }
            Token::End => Err(self.error_here("the expression ends where an operand is expected")),
            Token::Symbol(c) => Err(self.error_here(&format!("expected an operand, found `{c}`"))),
        }
    }

    /// The arguments of function `f`, the name consumed and `(` next.
    fn call(&mut self, f: usize) -> Result<Node, ExpressionError> {
        self.next += 1;
        let mut args = vec![self.expr()?];
        while self.peek() == Token::Symbol(',') {
            self.next += 1;
            args.push(self.expr()?);
        }
        self.expect(')', "expected `,` or `)`")?;
        let (name, _, expected) = FUNCTIONS[f];
        if args.len() != expected {
            return Err(ExpressionError::Arity {
                text: self.text.to_string(),
                name: name.to_string(),
                expected,
                found: args.len(),
            });
        }
        Ok(Node::Call(f, args))
    }

    /// "x, y, z and t" (and the law's variables).
    fn allowed_names(&self) -> String {
        let names: Vec<&str> = (VARIABLES.iter().zip(self.allowed))
            .filter_map(|(v, a)| a.then_some(*v))
            .collect();
        let (last, rest) = names.split_last().expect("x, y, z, t always allowed");
        format!("{} and {last}", rest.join(", "))
    }

    fn expect(&mut self, symbol: char, message: &str) -> Result<(), ExpressionError> {
        if self.peek() == Token::Symbol(symbol) {
            self.next += 1;
            Ok(())
        } else {
            Err(self.error_here(message))
        }
    }
}

/// [`ExpressionError::TooLarge`] with the text's first 40 characters.
fn too_large(text: &str, what: &'static str, limit: usize) -> ExpressionError {
    ExpressionError::TooLarge {
        start: text.chars().take(40).collect(),
        what,
        limit,
    }
}

/// A parse error at byte offset `at`, reported as a 1-based column. A text longer than 120
/// characters is shown as the 40 characters on each side of the column (a 4 kB formula is not
/// echoed whole).
fn parse_error(text: &str, at: usize, message: &str) -> ExpressionError {
    let column = text[..at].chars().count() + 1;
    let n = text.chars().count();
    let shown = if n <= 120 {
        text.to_string()
    } else {
        let from = (column - 1).saturating_sub(40);
        let excerpt: String = text.chars().skip(from).take(80).collect();
        let before = if from > 0 { "…" } else { "" };
        let after = if from + 80 < n { "…" } else { "" };
        format!("{before}{excerpt}{after}")
    };
    ExpressionError::Parse {
        text: shown,
        message: format!("{message} (column {column})"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(text: &str, x: [f64; 3], t: f64) -> f64 {
        Expression::parse(text).unwrap_or_else(|e| panic!("{e}")).eval(x, t)
    }

    #[test]
    fn expressions_agree_with_rust() {
        let points = [
            ([0.3, -1.7, 2.2], 0.7),
            ([4.0, 0.5, -0.25], 2.5),
            ([-2.0, 3.0, 1.0], 0.0),
        ];
        type Reference = fn([f64; 3], f64) -> f64;
        let cases: [(&str, Reference); 14] = [
            ("-20*t*y/sqrt(x^2+y^2)", |x, t| {
                -20.0 * t * x[1] / (x[0] * x[0] + x[1] * x[1]).sqrt()
            }),
            ("800*t", |_, t| 800.0 * t),
            ("-x^2", |x, _| -(x[0] * x[0])),
            ("exp(-x^2)", |x, _| (-(x[0] * x[0])).exp()),
            ("2^3^z", |x, _| 2f64.powf(3f64.powf(x[2]))),
            ("2^-x", |x, _| 2f64.powf(-x[0])),
            ("x - y - z", |x, _| x[0] - x[1] - x[2]),
            ("x / y / 2", |x, _| x[0] / x[1] / 2.0),
            ("-x*y + -(z)", |x, _| -x[0] * x[1] + -x[2]),
            ("min(x, y) * max(z, 1e-3) + abs(y)", |x, _| {
                x[0].min(x[1]) * x[2].max(1e-3) + x[1].abs()
            }),
            ("sin(pi*x) + cos(y)*tan(0.1*z)", |x, _| {
                (std::f64::consts::PI * x[0]).sin() + x[1].cos() * (0.1 * x[2]).tan()
            }),
            ("log(e) + ln(abs(x)+1) + log10(100)", |x, _| {
                std::f64::consts::E.ln() + (x[0].abs() + 1.0).ln() + 100f64.log10()
            }),
            ("atan2(y, x) + 1.5E+2 + .5", |x, _| x[1].atan2(x[0]) + 150.0 + 0.5),
            ("x**2 + 2*t", |x, t| x[0] * x[0] + 2.0 * t),
        ];
        for (text, reference) in cases {
            for (x, t) in points {
                assert_bits(text, eval(text, x, t), reference(x, t));
            }
        }
    }

    /// The same bits (any NaN for a NaN).
    fn assert_bits(text: &str, got: f64, want: f64) {
        assert!(
            got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
            "{text}: {got:e} vs {want:e}"
        );
    }

    /// The program's arithmetic is Rust's, written the same way, to the bit: precedence,
    /// chains, powers (x^2 of a variable is x·x, any other power `powf`), every function,
    /// constants folded.
    #[test]
    fn values_are_bit_identical_to_rust() {
        type Reference = fn([f64; 3], f64) -> f64;
        let cases: Vec<(&str, Reference)> = vec![
            ("x + y - z + t - x", |x, t| x[0] + x[1] - x[2] + t - x[0]),
            ("x * y / z * t / 3", |x, t| x[0] * x[1] / x[2] * t / 3.0),
            ("x - y*z + t/x - 2*y", |x, t| x[0] - x[1] * x[2] + t / x[0] - 2.0 * x[1]),
            ("2*3*x + x*2*3", |x, _| 6.0 * x[0] + x[0] * 2.0 * 3.0),
            ("0.1 + 0.2 + x", |x, _| 0.1 + 0.2 + x[0]),
            ("x + 0.1 + 0.2", |x, _| x[0] + 0.1 + 0.2),
            ("-2^2*x", |x, _| -(2f64.powf(2.0)) * x[0]),
            ("x^2 + (x+1)^2 + x^2.5 + y^x", |x, _| {
                x[0] * x[0] + (x[0] + 1.0).powf(2.0) + x[0].powf(2.5) + x[1].powf(x[0])
            }),
            ("x^(1+1) - x^-1", |x, _| x[0].powf(1.0 + 1.0) - x[0].powf(-1.0)),
            ("2^3^z + 2^-x", |x, _| 2f64.powf(3f64.powf(x[2])) + 2f64.powf(-x[0])),
            ("-(-(x))*-y", |x, _| -(-x[0]) * -x[1]),
            (
                "sin(x) + cos(y) + tan(z) + asin(x/10) + acos(y/10) + atan(z)",
                |x, _| x[0].sin() + x[1].cos() + x[2].tan() + (x[0] / 10.0).asin() + (x[1] / 10.0).acos() + x[2].atan(),
            ),
            ("sinh(x) * cosh(y) / tanh(z) - exp(t)", |x, t| {
                x[0].sinh() * x[1].cosh() / x[2].tanh() - t.exp()
            }),
            ("log(abs(x)) + ln(abs(y)) + log10(abs(z)) + sqrt(abs(x*y))", |x, _| {
                x[0].abs().ln() + x[1].abs().ln() + x[2].abs().log10() + (x[0] * x[1]).abs().sqrt()
            }),
            ("min(x, y) - max(y, z)*atan2(z, x) + atan2(-1, -x)", |x, _| {
                x[0].min(x[1]) - x[1].max(x[2]) * x[2].atan2(x[0]) + (-1f64).atan2(-x[0])
            }),
            ("sqrt(x)", |x, _| x[0].sqrt()),
            ("1/(x-x)", |x, _| 1.0 / (x[0] - x[0])),
            ("pi*e*x", |x, _| std::f64::consts::PI * std::f64::consts::E * x[0]),
        ];
        let points = [
            ([0.3, -1.7, 2.2], 0.7),
            ([4.0, 0.5, -0.25], 2.5),
            ([-2.0, 3.0, 1.0], 0.0),
            ([1e-300, 7.0, -1e10], 1e5),
        ];
        for (text, reference) in cases {
            for (x, t) in points {
                assert_bits(text, eval(text, x, t), reference(x, t));
            }
        }
        // A long mixed chain, from the left.
        let text = format!("x*y{}+z/x-t", "+z/x-t+x*y".repeat(59));
        let ([x, y, z], t) = ([0.3, -1.7, 2.2], 0.7);
        let mut sum = x * y;
        for _ in 0..59 {
            sum = sum + z / x - t + x * y;
        }
        sum = sum + z / x - t;
        assert_bits(&text, eval(&text, [x, y, z], t), sum);
    }

    #[test]
    fn constant_expressions_are_folded() {
        let e = Expression::parse("2^3^2 - -1").unwrap();
        assert!(matches!(e.body, Body::Constant(v) if v == 513.0));
        assert!(!e.uses_space() && !e.uses_time());
    }

    #[test]
    fn dependencies_are_detected() {
        let e = Expression::parse("3 + 2*t").unwrap();
        assert!(e.uses_time() && !e.uses_space());
        let e = Expression::parse("z").unwrap();
        assert!(e.uses_space() && !e.uses_time());
        assert_eq!(e.eval([1.0, 2.0, 3.0], 4.0), 3.0);
        assert_eq!(e.text(), "z");
    }

    #[test]
    fn ieee_values_pass_through() {
        assert_eq!(eval("1/(x-2)", [2.0, 0.0, 0.0], 0.0), f64::INFINITY);
        assert!(eval("sqrt(x-100)", [2.0, 0.0, 0.0], 0.0).is_nan());
    }

    #[test]
    fn unknown_variable_is_named() {
        let err = Expression::parse("q*x").unwrap_err();
        assert_eq!(
            err,
            ExpressionError::UnknownVariable {
                text: "q*x".into(),
                name: "q".into(),
                allowed: "x, y, z and t".into()
            }
        );
        let message = err.to_string();
        assert!(message.contains("`q`") && message.contains("q*x") && message.contains("x, y, z and t"));
    }

    #[test]
    fn unknown_function_is_named() {
        let err = Expression::parse("1 + foo(x)").unwrap_err();
        assert!(
            matches!(&err, ExpressionError::UnknownFunction { text, name } if text == "1 + foo(x)" && name == "foo")
        );
        assert!(err.to_string().contains("sqrt"));
    }

    #[test]
    fn syntax_errors_name_the_text_and_column() {
        for (text, fragment) in [
            ("sin(x", "expected `,` or `)` (column 6)"),
            ("x +* y", "found `*` (column 4)"),
            ("2x", "expected an operator (column 2)"),
            ("", "empty"),
            ("x)", "unmatched `)`"),
            ("1e999", "range"),
            ("x # 2", "unexpected character `#`"),
            ("sin x", "parentheses"),
            ("x(2)", "is a variable"),
        ] {
            match Expression::parse(text) {
                Err(ExpressionError::Parse { text: t, message }) => {
                    assert_eq!(t, text);
                    assert!(message.contains(fragment), "{text}: {message}");
                }
                other => panic!("{text}: expected a parse error, got {other:?}"),
            }
        }
        // A long text is shown around the column only.
        let long = format!("{}+)+{}", vec!["x"; 1000].join("+"), vec!["y"; 100].join("+"));
        let e = Expression::parse(&long).unwrap_err().to_string();
        assert!(e.len() < 300 && e.contains("column 2001") && e.contains("x+)+y"), "{e}");
    }

    #[test]
    fn arity_is_checked() {
        let err = Expression::parse("min(1, 2, x)").unwrap_err();
        assert!(matches!(
            err,
            ExpressionError::Arity {
                expected: 2,
                found: 3,
                ..
            }
        ));
        assert!(matches!(
            Expression::parse("sqrt(x, y)"),
            Err(ExpressionError::Arity { .. })
        ));
    }

    #[test]
    fn law_variables_only_where_allowed() {
        let mu = Expression::parse_with("0.8*exp(-100*r) + 0.2 + 0*theta*x", &["r", "theta"]).unwrap();
        assert!(mu.uses("r") && mu.uses("theta") && !mu.uses("t"));
        assert!((mu.eval_with([1.0, 0.0, 0.0], 0.0, [0.01, 5.0]) - (0.8 * (-1.0f64).exp() + 0.2)).abs() < 1e-15);
        // A load may not use r: the error lists what it may use.
        let err = Expression::parse("r*x").unwrap_err();
        assert!(err.to_string().contains("x, y, z and t"), "{err}");
        let err = Expression::parse_with("theta", &["r"]).unwrap_err();
        assert!(err.to_string().contains("x, y, z, t and r"), "{err}");
    }

    /// ∂/∂r at r = v (θ = 0.9, x = 0.3, t = 0.7).
    fn slope(f: &Expression, v: f64) -> f64 {
        f.derivative("r").eval_with([0.3, 0.0, 0.0], 0.7, [v, 0.9])
    }

    #[test]
    fn derivatives_agree_with_differences() {
        let cases = [
            "0.8*exp(-100*r) + 0.2",
            "0.5*theta - 5*sin(theta/5) + r*theta",
            "x*r^2 + t*sqrt(1 + r)",
            "tanh(3*r)/(1 + r^1.5)",
            "r^r + 2^r + (r+1)^-2.5 + (-2)^2*r",
            "sin(r)*cos(r)/tan(r+1) + asin(r/3) + acos(r/4) + atan(r)",
            "sinh(r) + cosh(r) + log(r) + ln(1+r) + log10(r) + exp(r/x)",
            "abs(r - 1) + min(r, 1 - r) + max(r*r, 0.5) + atan2(r, 1 - r) + atan2(0.3, r)",
        ];
        for text in cases {
            let f = Expression::parse_with(text, &["r", "theta"]).unwrap();
            for v in [0.003, 0.4, 0.9, 2.5] {
                let at = |v: f64| f.eval_with([0.3, 0.0, 0.0], 0.7, [v, 0.9]);
                let h = 1e-6 * (1.0 + v);
                let fd = (at(v + h) - at(v - h)) / (2.0 * h);
                let exact = slope(&f, v);
                assert!(
                    (fd - exact).abs() <= 1e-6 * (1.0 + exact.abs()),
                    "{text} at {v}: {exact} vs {fd}"
                );
            }
        }
    }

    #[test]
    fn derivatives_agree_with_hand_written_ones() {
        type Rule = fn(f64) -> f64;
        let cases: Vec<(&str, Rule)> = vec![
            ("sin(2*r)", |r| 2.0 * (2.0 * r).cos()),
            ("cos(r)", |r| -r.sin()),
            ("tan(r)", |r| 1.0 / (r.cos() * r.cos())),
            ("asin(r/2)", |r| 0.5 / (1.0 - r * r / 4.0).sqrt()),
            ("acos(r/2)", |r| -0.5 / (1.0 - r * r / 4.0).sqrt()),
            ("atan(r)", |r| 1.0 / (1.0 + r * r)),
            ("sinh(r)", |r| r.cosh()),
            ("cosh(r)", |r| r.sinh()),
            ("tanh(r)", |r| 1.0 / (r.cosh() * r.cosh())),
            ("exp(-3*r)", |r| -3.0 * (-3.0 * r).exp()),
            ("log(r)", |r| 1.0 / r),
            ("ln(r)", |r| 1.0 / r),
            ("log10(r)", |r| 1.0 / (r * std::f64::consts::LN_10)),
            ("sqrt(r)", |r| 0.5 / r.sqrt()),
            ("abs(r - 0.5)", |r| if r > 0.5 { 1.0 } else { -1.0 }),
            ("min(r, 0.5)", |r| if r < 0.5 { 1.0 } else { 0.0 }),
            ("max(r, 0.5)", |r| if r > 0.5 { 1.0 } else { 0.0 }),
            ("min(0.5, 2*r)", |r| if 2.0 * r < 0.5 { 2.0 } else { 0.0 }),
            ("atan2(r, 2)", |r| 2.0 / (r * r + 4.0)),
            ("atan2(2, r)", |r| -2.0 / (r * r + 4.0)),
            ("r^3", |r| 3.0 * r * r),
            ("r^2", |r| 2.0 * r),
            ("3^r", |r| 3f64.powf(r) * 3f64.ln()),
            ("r^r", |r| r.powf(r) * (r.ln() + 1.0)),
            ("(r-5)^3", |r| 3.0 * (r - 5.0) * (r - 5.0)),
            ("1/r", |r| -1.0 / (r * r)),
            ("r*r*r*r", |r| 4.0 * r * r * r),
            ("-r/(1+r)", |r| -1.0 / ((1.0 + r) * (1.0 + r))),
        ];
        for (text, rule) in cases {
            let f = Expression::parse_with(text, &["r"]).unwrap();
            for r in [0.1, 0.3, 0.7, 1.9] {
                let (got, want) = (slope(&f, r), rule(r));
                assert!(
                    (got - want).abs() <= 4e-15 * want.abs().max(1.0),
                    "{text} at {r}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn derivatives_at_the_kinks_and_in_other_variables() {
        let f = |text: &str| Expression::parse_with(text, &["r", "theta"]).unwrap();
        // abs: the right derivative at the kink; min and max: the first argument's on a tie.
        assert_eq!(slope(&f("abs(r - 0.5)"), 0.5), 1.0);
        assert_eq!(slope(&f("abs(0.5 - r)"), 0.5), -1.0);
        assert_eq!(slope(&f("min(2*r, 1)"), 0.5), 2.0);
        assert_eq!(slope(&f("min(1, 2*r)"), 0.5), 0.0);
        assert_eq!(slope(&f("max(3*r, 1.5)"), 0.5), 3.0);
        // A negative base with a constant exponent.
        assert!((slope(&f("(r - 2)^3"), 0.5) - 3.0 * 1.5 * 1.5).abs() < 1e-14);
        assert_eq!(slope(&f("(r - 2)^2"), 0.5), -3.0);
        // A part that does not depend on r has derivative 0, even where it is infinite.
        let g = f("sqrt(x - 0.3)*r + log(x - 0.3)");
        assert_eq!(g.derivative("r").eval_with([0.3, 0.0, 0.0], 0.0, [1.0, 0.0]), 0.0);
        // Constant in r: the constant 0; the derivative in the other variables.
        let h = f("x*y + t*theta^2");
        assert_eq!(h.derivative("r").eval_with([1.0, 2.0, 0.0], 1.0, [0.5, 3.0]), 0.0);
        assert!(matches!(h.derivative("r").body, Body::Constant(v) if v == 0.0));
        assert_eq!(h.derivative("theta").eval_with([1.0, 2.0, 0.0], 1.5, [0.5, 3.0]), 9.0);
        assert_eq!(h.derivative("y").eval_with([1.5, 2.0, 0.0], 1.5, [0.5, 3.0]), 1.5);
        assert_eq!(h.derivative("t").text(), "d/dt (x*y + t*theta^2)");
        assert_eq!(Expression::parse("7").unwrap().derivative("x").eval([0.0; 3], 0.0), 0.0);
    }

    #[test]
    #[should_panic(expected = "not one of the variables")]
    fn derivative_in_an_unknown_variable_panics() {
        Expression::parse("x").unwrap().derivative("q");
    }

    /// The program has at most one instruction per token and needs a stack as deep as the
    /// nesting (plus one per pending operand), not as long as the chains: evaluation is
    /// linear in the text.
    #[test]
    fn programs_are_linear_in_the_text() {
        let program = |text: &str| match Expression::parse(text).unwrap().body {
            Body::Program { program, .. } => program,
            Body::Constant(_) => panic!("{text} is constant"),
        };
        for n in [64, 1000, 2000] {
            for op in ["+", "*", "-", "/"] {
                let text = vec!["x"; n].join(op);
                let p = program(&text);
                assert_eq!((p.ops.len(), p.stack), (2 * n - 1, 2), "{op} {n}");
            }
        }
        let p = program(&vec!["x*y+z"; 600].join("-"));
        // Five instructions per `x*y+z`, one per `-` between them.
        assert_eq!((p.ops.len(), p.stack), (6 * 600 - 1, 3));
        // Parenthesized from the right: the stack grows with the nesting (bounded by it).
        let nested = format!("{}x{}", "(x+".repeat(90), ")".repeat(90));
        assert_eq!(program(&nested).stack, 91);
        // Constants are folded: `-20` and `2*3` are one instruction each.
        let p = program("-20*t*2*3 + 2*3*x");
        assert_eq!(
            p.ops,
            [
                Op::Const(-20.0),
                Op::Var(3),
                Op::Mul,
                Op::Const(2.0),
                Op::Mul,
                Op::Const(3.0),
                Op::Mul,
                Op::Const(6.0),
                Op::Var(0),
                Op::Mul,
                Op::Add
            ]
        );
    }

    #[test]
    fn long_chains_parse_evaluate_and_differentiate() {
        let sum = Expression::parse_with(&vec!["r"; 2000].join("+"), &["r"]).unwrap();
        assert_eq!(sum.eval_with([0.0; 3], 0.0, [1.5, 0.0]), 3000.0);
        assert_eq!(slope(&sum, 1.5), 2000.0);
        let product = Expression::parse_with(&vec!["r"; 2000].join("*"), &["r"]).unwrap();
        assert_eq!(product.eval_with([0.0; 3], 0.0, [1.0, 0.0]), 1.0);
        assert_eq!(slope(&product, 1.0), 2000.0);
        // Beyond a stack of 32: the heap.
        let nested = Expression::parse_with(&format!("{}r{}", "(r*".repeat(60), ")".repeat(60)), &["r"]).unwrap();
        assert_eq!(nested.eval_with([0.0; 3], 0.0, [1.0, 0.0]), 1.0);
        assert_eq!(slope(&nested, 1.0), 61.0);
    }

    #[test]
    fn long_and_deep_expressions_are_refused_not_a_stack_overflow() {
        let deep = format!("{}x{}", "(".repeat(9000), ")".repeat(9000));
        let e = Expression::parse(&deep).unwrap_err();
        assert!(matches!(e, ExpressionError::TooLarge { .. }), "{e}");
        let nested = format!("{}x{}", "(".repeat(150), ")".repeat(150));
        assert!(Expression::parse(&nested)
            .unwrap_err()
            .to_string()
            .contains("nested deeper"));
        assert!(Expression::parse(&format!("{}x", "-".repeat(500))).is_err());
        let long = vec!["x"; 26_000].join("+");
        let e = Expression::parse(&long).unwrap_err().to_string();
        assert!(e.contains("4096") && e.contains("x+x+"), "{e}");
        // Within the limits: a long sum parses and evaluates.
        let sum = vec!["x"; 1500].join("+");
        assert_eq!(Expression::parse(&sum).unwrap().eval([1.0, 0.0, 0.0], 0.0), 1500.0);
        let fifty = format!("{}x{}", "(".repeat(50), ")".repeat(50));
        assert_eq!(Expression::parse(&fifty).unwrap().eval([2.0, 0.0, 0.0], 0.0), 2.0);
    }

    /// The depth of a syntax tree (a leaf is 1).
    fn tree_depth(node: &Node) -> usize {
        1 + match node {
            Node::Number(_) | Node::Variable(_) => 0,
            Node::Negate(a) => tree_depth(a),
            Node::Chain(first, rest) => rest
                .iter()
                .map(|(_, a)| tree_depth(a))
                .fold(tree_depth(first), usize::max),
            Node::Power(a, b) => tree_depth(a).max(tree_depth(b)),
            Node::Call(_, args) => args.iter().map(tree_depth).max().unwrap_or(0),
        }
    }

    fn tree(text: &str) -> Node {
        let mut allowed = [false; VARIABLES.len()];
        allowed[..SPACE_TIME].fill(true);
        Parser::new(text, allowed).unwrap().parse().unwrap()
    }

    #[test]
    fn chains_are_flat_and_the_depth_is_bounded_by_the_nesting() {
        // 2000 terms: one chain of leaves, not a tree 2000 deep.
        let sum = vec!["x"; 2000].join("+");
        assert_eq!(tree_depth(&tree(&sum)), 2);
        let mixed = vec!["x*y/z"; 500].join("-");
        assert_eq!(tree_depth(&tree(&mixed)), 3);
        assert_eq!(Expression::parse(&sum).unwrap().eval([1.0, 0.0, 0.0], 0.0), 2000.0);
        // The deepest nesting allowed: within 4 levels per nesting level.
        let mut deepest = "x".to_string();
        for _ in 0..MAX_EXPRESSION_DEPTH - 1 {
            deepest = format!("sin(x*{deepest}+1)^2");
        }
        let depth = tree_depth(&tree(&deepest));
        assert!(depth <= 4 * (MAX_EXPRESSION_DEPTH + 1), "{depth}");
        assert!(depth > 3 * MAX_EXPRESSION_DEPTH, "{depth}: the test reaches the bound");
    }

    #[test]
    fn expressions_are_send_and_sync() {
        fn check<T: Send + Sync>() {}
        check::<Expression>();
    }
}
