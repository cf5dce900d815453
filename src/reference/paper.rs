//! The calibration fits of the paper this model comes from (Clemmer,
//! Monti and Lechman 2024, section 2.3 and Fig. 2):
//! `reference_data/paper_fits.json` compiled in, and what the studies and
//! the harness derive from it. Depends on nothing else in the crate, so
//! every layer can read it.

/// The file the fits are read from, as reports cite it.
pub const FITS_FILE: &str = "reference_data/paper_fits.json";

/// The paper's fits, `reference_data/paper_fits.json` compiled in: the one
/// place their coefficients are written.
const PAPER_FITS_JSON: &str = include_str!("../../reference_data/paper_fits.json");

/// Coefficients of the paper's fits, read from [`PAPER_FITS_JSON`].
struct PaperFits {
    /// `K = k[0] - k[1] / (a_B + k[2])`.
    k: [f64; 3],
    /// `G/K = g[0] + g[1] a_B`.
    g_over_k: [f64; 2],
}

fn paper_fits() -> &'static PaperFits {
    static FITS: std::sync::OnceLock<PaperFits> = std::sync::OnceLock::new();
    FITS.get_or_init(|| {
        let json: serde_json::Value =
            serde_json::from_str(PAPER_FITS_JSON).expect("reference_data/paper_fits.json: JSON");
        let formula = |name: &str| {
            json["fits"][name]["formula"]
                .as_str()
                .unwrap_or_else(|| panic!("reference_data/paper_fits.json: no fits.{name}.formula"))
                .to_string()
        };
        PaperFits {
            k: coefficients(&formula("K"), &["", " - ", " / (a_B + ", ")"]),
            g_over_k: coefficients(&formula("G_over_K"), &["", " + ", " * a_B"]),
        }
    })
}

/// The `N` numbers between the literal `pieces` (`N + 1` of them) of
/// `formula`; panics if `formula` does not have that form.
fn coefficients<const N: usize>(formula: &str, pieces: &[&str]) -> [f64; N] {
    assert_eq!(pieces.len(), N + 1);
    let bad = || -> ! {
        panic!("reference_data/paper_fits.json: `{formula}` is not of the form {pieces:?}")
    };
    let mut rest = formula.strip_prefix(pieces[0]).unwrap_or_else(|| bad());
    let mut out = [0.0; N];
    for (c, piece) in out.iter_mut().zip(&pieces[1..]) {
        let end = if piece.is_empty() {
            rest.len()
        } else {
            rest.find(piece).unwrap_or_else(|| bad())
        };
        *c = rest[..end].trim().parse().unwrap_or_else(|_| bad());
        rest = &rest[end + piece.len()..];
    }
    if !rest.is_empty() {
        bad();
    }
    out
}

/// The paper's fit (reference_data/paper_fits.json): `K(a_B)`.
pub fn bulk_modulus(a_b: f64) -> f64 {
    let [c0, c1, c2] = paper_fits().k;
    c0 - c1 / (a_b + c2)
}

/// The paper's fit (reference_data/paper_fits.json): `G/K(a_B)`.
pub fn shear_to_bulk(a_b: f64) -> f64 {
    let [c0, c1] = paper_fits().g_over_k;
    c0 + c1 * a_b
}

/// Poisson's ratio of the fits at `a_b`, from `G/K` alone:
/// `(3 - 2 G/K) / (2 (3 + G/K))` (the calibration's tables and plots).
pub fn poisson_ratio(a_b: f64) -> f64 {
    let gk = shear_to_bulk(a_b);
    (3.0 - 2.0 * gk) / (2.0 * (3.0 + gk))
}

/// `K` and Poisson's ratio of the fits at `a_b`, the elastic constants of
/// a grain's `E_eff`. Poisson's ratio is taken from `K` and `G = (G/K) K`
/// by the file's `nu` formula, not from `G/K` alone as in
/// [`poisson_ratio`]: the two differ in the last bits, and the Hertz
/// studies' recorded `E_eff` were computed this way.
pub fn elastic_constants(a_b: f64) -> (f64, f64) {
    let k = bulk_modulus(a_b);
    (k, nu_of(k, shear_to_bulk(a_b) * k))
}

/// The file's `nu` formula. The same expression as
/// `analysis::moduli::poisson_ratio` (a test there holds the two equal bit
/// for bit), written out so that this module needs nothing from the layers
/// that use it.
fn nu_of(k: f64, g: f64) -> f64 {
    (3.0 * k - 2.0 * g) / (2.0 * (3.0 * k + g))
}

/// Where [`elastic_constants`] come from, as the Hertz studies record it.
pub fn elastic_constants_source(a_b: f64) -> String {
    format!("the paper's calibration fits at a_B = {a_b} ({FITS_FILE})")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Value of an arithmetic `formula` as written in paper_fits.json
    /// (numbers, `+ - * /`, parentheses, implicit products such as `3K` or
    /// `2 (...)`, variables from `vars`): the file read independently of
    /// the parser behind [`paper_fits`].
    fn evaluate(formula: &str, vars: &[(&str, f64)]) -> f64 {
        #[derive(Clone, Debug, PartialEq)]
        enum Token {
            Num(f64),
            Var(String),
            Op(char),
        }
        let mut tokens = Vec::new();
        let chars: Vec<char> = formula.chars().collect();
        let mut k = 0;
        while k < chars.len() {
            let c = chars[k];
            let start = k;
            if c.is_ascii_digit() || c == '.' {
                while k < chars.len() && (chars[k].is_ascii_digit() || chars[k] == '.') {
                    k += 1;
                }
                let text: String = chars[start..k].iter().collect();
                tokens.push(Token::Num(text.parse().unwrap()));
            } else if c.is_alphabetic() {
                while k < chars.len() && (chars[k].is_alphanumeric() || chars[k] == '_') {
                    k += 1;
                }
                tokens.push(Token::Var(chars[start..k].iter().collect()));
            } else {
                if !c.is_whitespace() {
                    assert!("+-*/()".contains(c), "`{c}` in `{formula}`");
                    tokens.push(Token::Op(c));
                }
                k += 1;
            }
        }
        struct Parser<'a> {
            tokens: Vec<Token>,
            at: usize,
            vars: &'a [(&'a str, f64)],
        }
        impl Parser<'_> {
            fn peek(&self) -> Option<&Token> {
                self.tokens.get(self.at)
            }
            fn expr(&mut self) -> f64 {
                let mut v = self.term();
                while let Some(Token::Op(op @ ('+' | '-'))) = self.peek().cloned() {
                    self.at += 1;
                    let t = self.term();
                    v = if op == '+' { v + t } else { v - t };
                }
                v
            }
            fn term(&mut self) -> f64 {
                let mut v = self.factor();
                loop {
                    match self.peek().cloned() {
                        Some(Token::Op('*')) => {
                            self.at += 1;
                            v *= self.factor();
                        }
                        Some(Token::Op('/')) => {
                            self.at += 1;
                            v /= self.factor();
                        }
                        // Implicit product: `3K`, `2 (3K + G)`.
                        Some(Token::Num(_) | Token::Var(_) | Token::Op('(')) => {
                            v *= self.factor();
                        }
                        _ => return v,
                    }
                }
            }
            fn factor(&mut self) -> f64 {
                let token = self.peek().cloned();
                self.at += 1;
                match token {
                    Some(Token::Num(x)) => x,
                    Some(Token::Var(name)) => {
                        self.vars
                            .iter()
                            .find(|(n, _)| *n == name)
                            .unwrap_or_else(|| panic!("no value for `{name}`"))
                            .1
                    }
                    Some(Token::Op('-')) => -self.factor(),
                    Some(Token::Op('(')) => {
                        let v = self.expr();
                        assert_eq!(self.peek(), Some(&Token::Op(')')));
                        self.at += 1;
                        v
                    }
                    other => panic!("unexpected {other:?}"),
                }
            }
        }
        let mut p = Parser {
            tokens,
            at: 0,
            vars,
        };
        let v = p.expr();
        assert_eq!(p.at, p.tokens.len(), "trailing tokens in `{formula}`");
        v
    }

    #[test]
    fn evaluate_reads_the_formula_notation() {
        assert_eq!(evaluate("1 - 6 / (a + 1)", &[("a", 2.0)]), -1.0);
        assert_eq!(
            evaluate("(3K - 2G) / (2 (3K + G))", &[("K", 1.0), ("G", 0.0)]),
            0.5
        );
        assert_eq!(evaluate("0.5 + 2 * x", &[("x", -1.0)]), -1.5);
    }

    /// Relative difference of two evaluations of the same formula with the
    /// same operations, at most in another order: a few roundings.
    const SAME_FORMULA: f64 = 4.0 * f64::EPSILON;

    #[test]
    fn paper_fits_are_those_of_reference_data_paper_fits_json() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/reference_data/paper_fits.json"
        );
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let fits = &json["fits"];
        let formula = |name: &str| fits[name]["formula"].as_str().unwrap();
        let range = |name: &str| {
            let r = fits[name]["valid_a_B"].as_array().unwrap();
            (r[0].as_f64().unwrap(), r[1].as_f64().unwrap())
        };
        for (name, code) in [
            ("K", bulk_modulus as fn(f64) -> f64),
            ("G_over_K", shear_to_bulk),
        ] {
            let (lo, hi) = range(name);
            assert!(lo < hi, "{name}: valid_a_B {lo} .. {hi}");
            for k in 0..=8 {
                let a_b = lo + (hi - lo) * k as f64 / 8.0;
                let file = evaluate(formula(name), &[("a_B", a_b)]);
                assert!(
                    (code(a_b) - file).abs() <= SAME_FORMULA * file.abs(),
                    "{name}({a_b}): code {} vs paper_fits.json {file}",
                    code(a_b)
                );
            }
        }
        for (k, g) in [(1.245, 0.747), (1.3, 1.4), (0.98, 0.2)] {
            let file = evaluate(formula("nu"), &[("K", k), ("G", g)]);
            assert!(
                (nu_of(k, g) - file).abs() <= SAME_FORMULA * file.abs(),
                "nu({k}, {g}): code {} vs paper_fits.json {file}",
                nu_of(k, g)
            );
        }
    }

    #[test]
    fn paper_fits_give_values_computed_by_hand_from_the_paper() {
        // K = 1.365 - 0.14 / (a_B + 1.168), G/K = 0.6 + 0.475 a_B (section
        // 2.3, Fig. 2), worked out by hand: 0.14 / 1.168 = 35/292,
        // 0.14 / 2.168 = 35/542, 0.14 / 0.368 = 35/92, 0.14 / 4.168 =
        // 35/1042. The literals carry 15 digits, so 1e-14 is round-off; a
        // change of the last printed digit of any coefficient moves one of
        // these values by 8e-6 or more.
        let hand = [
            (0.0, 1.245_136_986_301_37, 0.6),
            (1.0, 1.300_424_354_243_542, 1.075),
            (-0.8, 0.984_565_217_391_304, 0.22),
            (3.0, 1.331_410_748_560_461, 2.025),
        ];
        for (a_b, k, g_over_k) in hand {
            assert!(
                (bulk_modulus(a_b) - k).abs() < 1e-14,
                "K({a_b}) = {}, by hand {k}",
                bulk_modulus(a_b)
            );
            assert!(
                (shear_to_bulk(a_b) - g_over_k).abs() < 1e-14,
                "G/K({a_b}) = {}, by hand {g_over_k}",
                shear_to_bulk(a_b)
            );
        }
    }
}
