//! Expressions of x, y, z, t: parsed and checked once, evaluated many times.
//!
//! ## Why exmex, measured
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
//! exmex is chosen: maintained, licensed like us, allocation-free, thread-safe, and within 35 %
//! of the fastest candidate. Through [`Expression`], which writes the square of a variable as a
//! product (exmex's `^` is `powf`), the first expression takes 55 ns and `800*t` 27 ns
//! (`cargo run --release --example expression_bench`). Speed matters less than it seems: a load
//! whose datum does not depend on x is never evaluated at quadrature points ([`super::Load`]).
//!
//! ## Why our own grammar in front of it
//!
//! exmex (and mathexpr) bind unary minus tighter than `^`: `-x^2` is (−x)², so `exp(-x^2)`
//! would silently be exp(x²). exmex also reads `2^3^2` as (2³)², takes any unknown name for a
//! variable, and has no exponent in number literals (`1e-3`). So [`Expression::parse`] parses the
//! text itself with the usual precedence (the one of MOOSE's ParsedFunction and of Python),
//! names unknown variables and functions, and hands exmex a fully parenthesized canonical text
//! that exmex compiles once and evaluates. exmex never parses user text directly, and no other
//! module sees it.
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

use std::fmt;

use exmex::prelude::*;
use exmex::{literal_matcher_from_pattern, FloatOpsFactory, MatchLiteral};

/// Every variable an expression may use: the point (x, y, z) and t, which every expression
/// may use, then the arguments of the laws on Γ_C, which only the laws allow
/// ([`Expression::parse_with`]): the slip rate r and the temperature θ (`theta`).
const VARIABLES: [&str; 6] = ["x", "y", "z", "t", "r", "theta"];

/// The number of variables every expression may use (x, y, z, t).
const SPACE_TIME: usize = 4;

/// The functions of the grammar: our name, exmex's name, number of arguments.
const FUNCTIONS: [(&str, &str, usize); 18] = [
    ("sin", "sin", 1),
    ("cos", "cos", 1),
    ("tan", "tan", 1),
    ("asin", "asin", 1),
    ("acos", "acos", 1),
    ("atan", "atan", 1),
    ("sinh", "sinh", 1),
    ("cosh", "cosh", 1),
    ("tanh", "tanh", 1),
    ("exp", "exp", 1),
    ("log", "ln", 1),
    ("ln", "ln", 1),
    ("log10", "log10", 1),
    ("sqrt", "sqrt", 1),
    ("abs", "abs", 1),
    ("min", "min", 2),
    ("max", "max", 2),
    ("atan2", "atan2", 2),
];

/// Named constants, replaced by their values at parse time.
const CONSTANTS: [(&str, f64); 2] = [("pi", std::f64::consts::PI), ("e", std::f64::consts::E)];

// exmex's default literals have no exponent; the canonical text writes numbers with Rust's
// shortest round-trip formatting (`{:?}`), which uses one for very small and large values.
literal_matcher_from_pattern!(FloatLiteral, r"^[0-9]+(\.[0-9]+)?([eE][+-]?[0-9]+)?");

/// exmex's compiled form with its default float operators and our literals.
type Compiled = FlatEx<f64, FloatOpsFactory<f64>, FloatLiteral>;

/// The longest expression text, in bytes: a datum or a law is a formula, not data (a longer
/// text would build a syntax tree too deep for the stack).
pub const MAX_EXPRESSION_BYTES: usize = 4096;

/// The deepest nesting of parentheses, signs and powers in an expression.
pub const MAX_EXPRESSION_DEPTH: usize = 100;

/// Errors of [`Expression::parse`]; each names the text it is about.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExpressionError {
    /// The text is not an expression of the grammar (or exmex refused the canonical form).
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
    /// exmex takes the values of the variables it found in alphabetical order (r, t, theta, x,
    /// y, z); `slots[k]` is the index in [`VARIABLES`] of its k-th one.
    Compiled { compiled: Box<Compiled>, slots: Vec<usize> },
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
            let canonical = node.canonical();
            let parse_error = |e: exmex::ExError| ExpressionError::Parse {
                text: text.to_string(),
                message: format!("exmex rejected the canonical form `{canonical}`: {e}"),
            };
            let compiled = Compiled::parse(&canonical).map_err(parse_error)?;
            let slots = compiled
                .var_names()
                .iter()
                .map(|name| VARIABLES.iter().position(|v| v == name).expect("only our variables"))
                .collect();
            Body::Compiled {
                compiled: Box::new(compiled),
                slots,
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
    /// exmex's symbolic differentiation; `None` where the expression uses a function exmex does
    /// not differentiate (`abs`, `min`, `max`, `atan2`). The derivative takes the same
    /// arguments as the expression.
    pub fn derivative(&self, variable: &str) -> Option<Expression> {
        let k = VARIABLES.iter().position(|v| *v == variable)?;
        let text = format!("d/d{variable} ({})", self.text);
        let body = match &self.body {
            Body::Compiled { compiled, slots } if self.uses[k] => {
                let index = slots.iter().position(|&s| s == k)?;
                let derivative = compiled.as_ref().clone().partial(index).ok()?;
                Body::Compiled {
                    compiled: Box::new(derivative),
                    slots: slots.clone(),
                }
            }
            _ => Body::Constant(0.0),
        };
        Some(Expression {
            text,
            body,
            uses: self.uses,
        })
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
        match &self.body {
            Body::Constant(value) => *value,
            Body::Compiled { compiled, slots } => {
                let all = [x[0], x[1], x[2], t, laws[0], laws[1]];
                let mut values = [0.0; VARIABLES.len()];
                for (value, &slot) in values.iter_mut().zip(slots) {
                    *value = all[slot];
                }
                // The slice has exactly the variables exmex found, so evaluation cannot fail;
                // NaN would surface as a non-finite load rather than a panic.
                compiled.eval(&values[..slots.len()]).unwrap_or(f64::NAN)
            }
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

    /// Fully parenthesized text in exmex's syntax: every precedence decision is ours.
    fn canonical(&self) -> String {
        match self {
            Node::Number(v) => format!("{v:?}"),
            Node::Variable(k) => VARIABLES[*k].to_string(),
            Node::Negate(a) => format!("(-({}))", a.canonical()),
            // exmex's `^` is `powf`; a square of a variable is a product.
            Node::Power(a, b) if Node::is_square_of_variable(a, b) => {
                let x = a.canonical();
                format!("({x} * {x})")
            }
            Node::Power(a, b) => format!("(({}) ^ ({}))", a.canonical(), b.canonical()),
            Node::Chain(first, rest) => rest.iter().fold(first.canonical(), |text, (op, a)| {
                format!("(({text}) {op} ({}))", a.canonical())
            }),
            Node::Call(f, args) => {
                let name = FUNCTIONS[*f].1;
                match args.as_slice() {
                    [a] => format!("{name}({})", a.canonical()),
                    // exmex's two-argument functions are binary operators: `(a) min (b)`.
                    [a, b] => format!("(({}) {name} ({}))", a.canonical(), b.canonical()),
                    _ => unreachable!("arity checked by the parser"),
                }
            }
        }
    }

    /// The value of a tree without variables.
    fn value(&self) -> f64 {
        match self {
            Node::Number(v) => *v,
            Node::Variable(_) => unreachable!("only called on constant trees"),
            Node::Negate(a) => -a.value(),
            Node::Chain(first, rest) => rest.iter().fold(first.value(), |a, (op, b)| {
                let b = b.value();
                match op {
                    '+' => a + b,
                    '-' => a - b,
                    '*' => a * b,
                    _ => a / b,
                }
            }),
            Node::Power(a, b) => a.value().powf(b.value()),
            Node::Call(f, args) => {
                let a = args[0].value();
                match FUNCTIONS[*f].0 {
                    "sin" => a.sin(),
                    "cos" => a.cos(),
                    "tan" => a.tan(),
                    "asin" => a.asin(),
                    "acos" => a.acos(),
                    "atan" => a.atan(),
                    "sinh" => a.sinh(),
                    "cosh" => a.cosh(),
                    "tanh" => a.tanh(),
                    "exp" => a.exp(),
                    "log" | "ln" => a.ln(),
                    "log10" => a.log10(),
                    "sqrt" => a.sqrt(),
                    "abs" => a.abs(),
                    "min" => a.min(args[1].value()),
                    "max" => a.max(args[1].value()),
                    "atan2" => a.atan2(args[1].value()),
                    other => unreachable!("function {other} missing from the constant evaluator"),
                }
            }
        }
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

/// A parse error at byte offset `at`, reported as a 1-based column.
fn parse_error(text: &str, at: usize, message: &str) -> ExpressionError {
    let column = text[..at].chars().count() + 1;
    ExpressionError::Parse {
        text: text.to_string(),
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
            ("-x*y + -(z)", |x, _| -x[0] * x[1] - x[2]),
            ("min(x, y) * max(z, 1e-3) + abs(y)", |x, _| {
                x[0].min(x[1]) * x[2].max(1e-3) + x[1].abs()
            }),
            ("sin(pi*x) + cos(y)*tan(0.1*z)", |x, _| {
                (std::f64::consts::PI * x[0]).sin() + x[1].cos() * (0.1 * x[2]).tan()
            }),
            ("log(e) + ln(abs(x)+1) + log10(100)", |x, _| {
                1.0 + (x[0].abs() + 1.0).ln() + 2.0
            }),
            ("atan2(y, x) + 1.5E+2 + .5", |x, _| x[1].atan2(x[0]) + 150.5),
            ("x**2 + 2*t", |x, t| x[0] * x[0] + 2.0 * t),
        ];
        for (text, reference) in cases {
            for (x, t) in points {
                let (got, want) = (eval(text, x, t), reference(x, t));
                assert!(
                    (got - want).abs() <= 1e-13 * (1.0 + want.abs()),
                    "{text} at {x:?}, t = {t}: {got} vs {want}"
                );
            }
        }
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

    #[test]
    fn symbolic_derivatives_agree_with_differences() {
        let cases = [
            "0.8*exp(-100*r) + 0.2",
            "0.5*theta - 5*sin(theta/5)",
            "x*r^2 + t*sqrt(1 + r)",
            "tanh(3*r)/(1 + r^1.5)",
        ];
        for text in cases {
            let f = Expression::parse_with(text, &["r", "theta"]).unwrap();
            let variable = if f.uses("theta") { "theta" } else { "r" };
            let df = f.derivative(variable).expect("differentiable");
            for v in [0.003, 0.4, 2.5] {
                let at = |v: f64| if variable == "r" { [v, 0.0] } else { [0.0, v] };
                let h = 1e-6 * (1.0 + v);
                let fd = (f.eval_with([0.3, 0.0, 0.0], 0.7, at(v + h)) - f.eval_with([0.3, 0.0, 0.0], 0.7, at(v - h)))
                    / (2.0 * h);
                let exact = df.eval_with([0.3, 0.0, 0.0], 0.7, at(v));
                assert!(
                    (fd - exact).abs() <= 1e-6 * (1.0 + exact.abs()),
                    "{text} at {v}: {exact} vs {fd}"
                );
            }
        }
        // Constant in r: derivative 0; abs has no symbolic derivative in exmex.
        let g = Expression::parse_with("x + t", &["r"]).unwrap();
        assert_eq!(
            g.derivative("r").unwrap().eval_with([1.0, 0.0, 0.0], 1.0, [0.5, 0.0]),
            0.0
        );
        assert!(Expression::parse_with("abs(r - 1)", &["r"])
            .unwrap()
            .derivative("r")
            .is_none());
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
