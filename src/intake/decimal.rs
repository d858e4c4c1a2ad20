//! Exact decimal arithmetic for unit conversions.
//!
//! A cell holds a decimal number as its author wrote it (`0,91`, `13.3788`); converting it to SI
//! with binary floating point (`0.932 × 1e-3`, `1073.15 − 273.15`) rounds twice and can land one
//! unit in the last place away from the number an SI file would hold (`0.000932`, `800`). Here
//! a conversion is carried out on the decimal digits exactly — multiplication by the unit's
//! factor, division by its divisor to [`GUARD_DIGITS`] significant digits with a sticky digit,
//! addition of its offset — and the result is rounded once, half to even, to
//! [`SIGNIFICANT`] significant digits before it is parsed as an `f64` (Rust's parser rounds
//! correctly). 15 digits are what every `f64` holds (DBL_DIG): a value exported from SI to
//! another unit with at least 15 significant digits, or stored as an `f64` by a spreadsheet, comes
//! back as the `f64` of the SI text; no instrument resolves more.
//!
//! Verified by the unit tests below (exactness of shifts and offsets, rounding, the round trip of
//! every value of the shipped crush files through kgf and lbf).

/// Significant digits a converted value is rounded to.
pub const SIGNIFICANT: usize = 15;

/// Digits a division is carried to before rounding (a remainder adds a sticky digit).
pub const GUARD_DIGITS: usize = 24;

/// A decimal number: `±digits × 10^exp`, digits most significant first, no leading zeros
/// (empty for zero).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Decimal {
    neg: bool,
    digits: Vec<u8>,
    exp: i64,
}

impl Decimal {
    /// Parses `[+-]digits[.digits][e[+-]digits]` (also `.5`, `5.`); None for anything else.
    pub fn parse(text: &str) -> Option<Decimal> {
        let s = text.trim();
        let (neg, s) = match s.as_bytes().first()? {
            b'-' => (true, &s[1..]),
            b'+' => (false, &s[1..]),
            _ => (false, s),
        };
        let (mantissa, exponent) = match s.find(['e', 'E']) {
            Some(k) => (&s[..k], Some(&s[k + 1..])),
            None => (s, None),
        };
        let (int, frac) = match mantissa.find('.') {
            Some(k) => (&mantissa[..k], &mantissa[k + 1..]),
            None => (mantissa, ""),
        };
        if int.is_empty() && frac.is_empty() {
            return None;
        }
        if !int.bytes().chain(frac.bytes()).all(|b| b.is_ascii_digit()) {
            return None;
        }
        let mut exp: i64 = match exponent {
            None => 0,
            Some(e) => {
                let (sign, body) = match e.as_bytes().first()? {
                    b'-' => (-1, &e[1..]),
                    b'+' => (1, &e[1..]),
                    _ => (1, e),
                };
                if body.is_empty() || body.len() > 9 || !body.bytes().all(|b| b.is_ascii_digit()) {
                    return None;
                }
                sign * body.parse::<i64>().ok()?
            }
        };
        exp -= frac.len() as i64;
        let digits: Vec<u8> = int.bytes().chain(frac.bytes()).map(|b| b - b'0').collect();
        Some(Decimal { neg, digits, exp }.normalised())
    }

    /// Strips leading zeros and trailing zeros (moving them into the exponent).
    fn normalised(mut self) -> Decimal {
        let lead = self.digits.iter().take_while(|&&d| d == 0).count();
        self.digits.drain(..lead);
        while self.digits.last() == Some(&0) {
            self.digits.pop();
            self.exp += 1;
        }
        if self.digits.is_empty() {
            self.neg = false;
            self.exp = 0;
        }
        self
    }

    /// The exact product.
    pub fn mul(&self, other: &Decimal) -> Decimal {
        if self.digits.is_empty() || other.digits.is_empty() {
            return Decimal { neg: false, digits: Vec::new(), exp: 0 };
        }
        // Schoolbook multiplication, least significant first.
        let (a, b): (Vec<u32>, Vec<u32>) = (self.digits.iter().rev().map(|&d| d as u32).collect(), other.digits.iter().rev().map(|&d| d as u32).collect());
        let mut acc = vec![0u32; a.len() + b.len()];
        for (i, &x) in a.iter().enumerate() {
            let mut carry = 0u32;
            for (j, &y) in b.iter().enumerate() {
                let t = acc[i + j] + x * y + carry;
                acc[i + j] = t % 10;
                carry = t / 10;
            }
            let mut k = i + b.len();
            while carry > 0 {
                let t = acc[k] + carry;
                acc[k] = t % 10;
                carry = t / 10;
                k += 1;
            }
        }
        let digits = acc.into_iter().rev().map(|d| d as u8).collect();
        Decimal { neg: self.neg != other.neg, digits, exp: self.exp + other.exp }.normalised()
    }

    /// The quotient by a positive integer divisor, to [`GUARD_DIGITS`] significant digits with a
    /// sticky last digit when the division is not exact.
    pub fn div_int(&self, divisor: u64) -> Decimal {
        assert!(divisor > 0, "division by zero");
        if self.digits.is_empty() {
            return self.clone();
        }
        let mut out = Vec::new();
        let mut rem: u128 = 0;
        let mut k = 0usize;
        let mut exp = self.exp;
        loop {
            let next = if k < self.digits.len() {
                self.digits[k] as u128
            } else {
                if rem == 0 || out.iter().skip_while(|&&d| d == 0).count() >= GUARD_DIGITS {
                    break;
                }
                exp -= 1;
                0
            };
            k += 1;
            let t = rem * 10 + next;
            out.push((t / divisor as u128) as u8);
            rem = t % divisor as u128;
        }
        if rem != 0 {
            out.push(1);
            exp -= 1;
        }
        Decimal { neg: self.neg, digits: out, exp }.normalised()
    }

    /// The exact sum.
    pub fn add(&self, other: &Decimal) -> Decimal {
        if other.digits.is_empty() {
            return self.clone();
        }
        if self.digits.is_empty() {
            return other.clone();
        }
        let exp = self.exp.min(other.exp);
        let widen = |d: &Decimal| -> Vec<i32> {
            let mut v: Vec<i32> = d.digits.iter().map(|&x| x as i32).collect();
            v.extend(std::iter::repeat_n(0, (d.exp - exp) as usize));
            v.reverse();
            v
        };
        let (a, b) = (widen(self), widen(other));
        let n = a.len().max(b.len()) + 1;
        let at = |v: &Vec<i32>, i: usize| v.get(i).copied().unwrap_or(0);
        // Magnitudes compared to subtract the smaller from the larger.
        let cmp = (0..n).rev().map(|i| at(&a, i).cmp(&at(&b, i))).find(|o| o.is_ne()).unwrap_or(std::cmp::Ordering::Equal);
        let (big, small, neg) = if cmp.is_ge() { (&a, &b, self.neg) } else { (&b, &a, other.neg) };
        let same = self.neg == other.neg;
        let mut out = Vec::with_capacity(n);
        let mut carry = 0;
        for i in 0..n {
            let t = if same { at(big, i) + at(small, i) + carry } else { at(big, i) - at(small, i) + carry };
            out.push(t.rem_euclid(10) as u8);
            carry = t.div_euclid(10);
        }
        out.reverse();
        Decimal { neg, digits: out, exp }.normalised()
    }

    /// Rounded half to even to `n` significant digits.
    pub fn round_significant(&self, n: usize) -> Decimal {
        if self.digits.len() <= n {
            return self.clone();
        }
        let cut = self.digits.len() - n;
        let mut kept: Vec<u8> = self.digits[..n].to_vec();
        let first = self.digits[n];
        let rest_nonzero = self.digits[n + 1..].iter().any(|&d| d != 0);
        let last_odd = kept[n - 1] % 2 == 1;
        let up = first > 5 || (first == 5 && (rest_nonzero || last_odd));
        let mut exp = self.exp + cut as i64;
        if up {
            let mut i = n;
            loop {
                if i == 0 {
                    kept.insert(0, 1);
                    kept.pop();
                    exp += 1;
                    break;
                }
                i -= 1;
                if kept[i] == 9 {
                    kept[i] = 0;
                } else {
                    kept[i] += 1;
                    break;
                }
            }
        }
        Decimal { neg: self.neg, digits: kept, exp }.normalised()
    }

    /// The number in plain positional notation (`0.000932`, `-17.5`, `1200`).
    pub fn to_plain(&self) -> String {
        if self.digits.is_empty() {
            return "0".into();
        }
        let d: String = self.digits.iter().map(|d| (b'0' + d) as char).collect();
        let sign = if self.neg { "-" } else { "" };
        let n = d.len() as i64;
        if self.exp >= 0 {
            format!("{sign}{d}{}", "0".repeat(self.exp as usize))
        } else if -self.exp < n {
            let k = (n + self.exp) as usize;
            format!("{sign}{}.{}", &d[..k], &d[k..])
        } else {
            format!("{sign}0.{}{d}", "0".repeat((-self.exp - n) as usize))
        }
    }

    /// The nearest `f64` (correctly rounded by Rust's parser).
    pub fn to_f64(&self) -> f64 {
        if self.digits.is_empty() {
            return 0.0;
        }
        let s: String = self.digits.iter().map(|d| (b'0' + d) as char).collect();
        let text = format!("{}{s}e{}", if self.neg { "-" } else { "" }, self.exp);
        text.parse().unwrap_or(f64::NAN)
    }
}

/// A linear conversion to SI: `si = value × scale / divisor + offset`, each part an exact
/// decimal.
#[derive(Debug, Clone, PartialEq)]
pub struct Conversion {
    scale: Decimal,
    divisor: u64,
    offset: Decimal,
}

impl Conversion {
    /// From decimal texts (`"9.80665"`, `1`, `"-273.15"`); None when a text is not a decimal
    /// or the divisor is 0.
    pub fn new(scale: &str, divisor: u64, offset: &str) -> Option<Conversion> {
        (divisor > 0).then_some(())?;
        Some(Conversion { scale: Decimal::parse(scale)?, divisor, offset: Decimal::parse(offset)? })
    }

    /// True for the identity (the value is taken as written).
    pub fn is_identity(&self) -> bool {
        self.divisor == 1 && self.offset.digits.is_empty() && self.scale.digits == [1] && self.scale.exp == 0 && !self.scale.neg
    }

    /// The SI value of a decimal text: exact arithmetic, then rounded to [`SIGNIFICANT`]
    /// digits (module docs); None when the text is not a decimal number.
    pub fn apply(&self, text: &str) -> Option<f64> {
        let v = Decimal::parse(text)?;
        if self.is_identity() {
            return Some(v.to_f64());
        }
        let mut x = v.mul(&self.scale);
        if self.divisor != 1 {
            x = x.div_int(self.divisor);
        }
        Some(x.add(&self.offset).round_significant(SIGNIFICANT).to_f64())
    }
}

impl Conversion {
    /// The inverse: a value given in SI (decimal text) in this unit, `(si − offset) × divisor /
    /// scale`, exact for shifts and offsets, else to [`GUARD_DIGITS`] digits, rounded to
    /// `significant` digits, in plain notation; None when the text is not a decimal number or
    /// the scale's digits do not fit an integer divisor.
    pub fn from_si(&self, text: &str, significant: usize) -> Option<String> {
        let v = Decimal::parse(text)?;
        let neg_offset = Decimal { neg: !self.offset.neg, ..self.offset.clone() }.normalised();
        let shifted = v.add(&neg_offset).mul(&Decimal { neg: false, digits: self.divisor.to_string().bytes().map(|b| b - b'0').collect(), exp: 0 }.normalised());
        // Dividing by scale = digits × 10^exp: divide by the digits, then shift by −exp.
        let digits: String = self.scale.digits.iter().map(|d| (b'0' + d) as char).collect();
        let q = shifted.div_int(digits.parse::<u64>().ok()?);
        let out = Decimal { exp: q.exp - self.scale.exp, ..q };
        Some(out.round_significant(significant).to_plain())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn conv(scale: &str, divisor: u64, offset: &str) -> Conversion {
        Conversion::new(scale, divisor, offset).unwrap()
    }

    #[test]
    fn parses_the_forms_a_cell_takes() {
        for (s, v) in [("0.91", 0.91), ("-1.5e-3", -1.5e-3), (".5", 0.5), ("5.", 5.0), ("+12", 12.0), ("0", 0.0), ("1E3", 1e3), ("000.000120", 1.2e-4)] {
            assert_eq!(Decimal::parse(s).unwrap().to_f64(), v, "{s}");
        }
        for s in ["", ".", "e5", "1e", "1.2.3", "0x10", "1,5", "--1", "1e+", "inf", "NaN", "1e9999999999"] {
            assert!(Decimal::parse(s).is_none(), "{s}");
        }
    }

    #[test]
    fn shifts_and_offsets_are_exact() {
        // Binary floating point gets these wrong: 0.932 * 1e-3 = 0.0009320000000000001 and
        // 1073.15 - 273.15 = 800.0000000000001.
        assert_ne!(0.932 * 1e-3, 0.000932);
        assert_eq!(conv("1e-3", 1, "0").apply("0.932"), Some(0.000932));
        assert_ne!(1073.15 - 273.15, 800.0);
        assert_eq!(conv("1", 1, "-273.15").apply("1073.15"), Some(800.0));
        assert_eq!(conv("1", 1, "-273.15").apply("293.15"), Some(20.0));
        assert_eq!(conv("1e-6", 1, "0").apply("912"), Some(0.000912));
        assert_eq!(conv("1e3", 1, "0").apply("-0.0175"), Some(-17.5));
    }

    #[test]
    fn rounding_is_half_to_even_with_carries() {
        let r = |s: &str, n| Decimal::parse(s).unwrap().round_significant(n).to_f64();
        assert_eq!(r("1.25", 2), 1.2);
        assert_eq!(r("1.35", 2), 1.4);
        assert_eq!(r("1.2500001", 2), 1.3);
        assert_eq!(r("9.99", 2), 10.0);
        assert_eq!(r("-9.95", 2), -10.0);
        assert_eq!(r("123", 5), 123.0);
    }

    #[test]
    fn division_is_carried_far_enough() {
        // 1/3 to 24 digits then rounded to 15.
        assert_eq!(Decimal::parse("1").unwrap().div_int(3).round_significant(15).to_f64(), 0.333333333333333);
        // psi: lbf / in² = 4.4482216152605 N / 0.00064516 m² = 6894.757293168361… Pa.
        let psi = conv("4.4482216152605e8", 64516, "0");
        assert_eq!(psi.apply("1"), Some(6894.75729316836)); // 6894.757293168361337 to 15 digits
        assert_eq!(psi.apply("145.0377"), Some(999999.739859365)); // 999999.7398593648410… to 15 digits
    }

    #[test]
    fn the_inverse_writes_plain_decimals() {
        assert_eq!(conv("1e-3", 1, "0").from_si("0.000932", 17).as_deref(), Some("0.932"));
        assert_eq!(conv("1e-6", 1, "0").from_si("0.00066", 17).as_deref(), Some("660"));
        assert_eq!(conv("1", 1, "-273.15").from_si("20", 17).as_deref(), Some("293.15"));
        assert_eq!(conv("9.80665", 1, "0").from_si("131.212977", 17).as_deref(), Some("13.38"));
        assert_eq!(conv("4.4482216152605e8", 64516, "0").from_si("6894.757293168361336722673", 15).as_deref(), Some("1"));
        // And back: a force exported in kgf to 17 digits is the SI value again.
        let kgf = conv("9.80665", 1, "0");
        assert_eq!(kgf.apply(&kgf.from_si("147.4", 17).unwrap()), Some(147.4));
    }

    #[test]
    fn sums_of_mixed_signs() {
        let a = |x: &str, y: &str| Decimal::parse(x).unwrap().add(&Decimal::parse(y).unwrap()).to_f64();
        assert_eq!(a("0.1", "0.2"), 0.3);
        assert_eq!(a("-273.15", "273.15"), 0.0);
        assert_eq!(a("100", "-273.15"), -173.15);
        assert_eq!(a("-5", "2.5"), -2.5);
    }

    #[test]
    fn forces_round_trip_through_kgf_and_lbf() {
        // Every force of the shipped crush files, written in kgf or lbf with 17 significant
        // digits (as an f64 in a spreadsheet holds it) and converted back, is the SI value.
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets");
        let mut n = 0;
        for file in ["crush_gen4.csv", "crush_bl1630.csv"] {
            let text = std::fs::read_to_string(root.join(file)).unwrap();
            for line in text.lines().skip(1) {
                let cell = line.split(',').nth(3).unwrap();
                let si: f64 = cell.parse().unwrap();
                for (scale, unit) in [("9.80665", "kgf"), ("4.4482216152605", "lbf")] {
                    let per: f64 = scale.parse().unwrap();
                    let exported = format!("{}", si / per);
                    assert_eq!(conv(scale, 1, "0").apply(&exported), Some(si), "{cell} N as {exported} {unit}");
                }
                n += 1;
            }
        }
        assert!(n > 90);
    }
}
