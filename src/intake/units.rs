//! The unit grammar: which units each quantity may be given in, and how a column header states
//! its unit.
//!
//! # Units
//!
//! | quantity | SI (inside partlife) | accepted (case does not matter) |
//! |---|---|---|
//! | length | m | m, mm, µm (`um`, `μm`) |
//! | force | N | N, kN, mN, kgf (`kp`; × 9.80665 N), lbf (× 4.4482216152605 N) |
//! | stress | Pa | Pa, kPa, MPa (`N/mm²`, `N/mm2`, `MN/m²`), GPa, kgf/mm² (`kp/mm²`; × 9.80665e6 Pa), psi (`lbf/in²`, `lb/in²` = 6894.757… Pa), ksi |
//! | temperature | °C | °C (`degC`, `C`, `ºC`), K (− 273.15) |
//! | velocity | m/s | m/s, mm/s |
//! | ratio | – | `-`, `1`, or none; `%` (× 0.01) |
//! | count | – | `-`, `1`, or none |
//!
//! Exact factors: kgf = 9.80665 N (standard gravity, CGPM 1901), lbf = 0.45359237 kg × 9.80665
//! m/s² (international pound, 1959), in = 0.0254 m, so psi = 4.4482216152605 / 0.00064516 Pa.
//! Conversions are exact decimal arithmetic rounded once ([`super::decimal`]).
//!
//! # Headers
//!
//! A header names its column and may state the unit, in one of these forms
//! ([`parse_header`]):
//!
//! * brackets or parentheses at the end: `D [mm]`, `d (µm)`, `F_max (kN)`, `T [°C]`;
//! * a slash, ISO 80000 style: `d/mm`, `v/(m/s)`;
//! * a snake-case suffix, partlife's own form: `diameter_m`, `crush_force_n`,
//!   `temperature_c`, `sigma_pa`, `v_m_s`.
//!
//! A name with no recognisable unit has none; a unit the study declares fills the gap
//! (`units = { diameter = "mm" }`).

/// A physical quantity a column may hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Quantity {
    /// Length (SI: m).
    Length,
    /// Force (SI: N).
    Force,
    /// Stress (SI: Pa).
    Stress,
    /// Temperature (partlife's internal unit: °C).
    Temperature,
    /// Velocity (SI: m/s).
    Velocity,
    /// A dimensionless ratio (roundness, a fraction).
    Ratio,
    /// A count (impacts).
    Count,
}

impl Quantity {
    /// The word used in messages.
    pub fn word(self) -> &'static str {
        match self {
            Quantity::Length => "a length",
            Quantity::Force => "a force",
            Quantity::Stress => "a stress",
            Quantity::Temperature => "a temperature",
            Quantity::Velocity => "a velocity",
            Quantity::Ratio => "a dimensionless ratio",
            Quantity::Count => "a count",
        }
    }

    /// The units accepted for it, as messages list them.
    pub fn accepted(self) -> String {
        let mut out: Vec<&str> = Vec::new();
        for u in UNITS.iter().filter(|u| u.quantity == self) {
            if !out.contains(&u.symbol) {
                out.push(u.symbol);
            }
        }
        out.join(", ")
    }

    /// True when a column of this quantity may have no unit.
    pub fn unitless(self) -> bool {
        matches!(self, Quantity::Ratio | Quantity::Count)
    }

    /// The internal unit's symbol.
    pub fn si(self) -> &'static str {
        match self {
            Quantity::Length => "m",
            Quantity::Force => "N",
            Quantity::Stress => "Pa",
            Quantity::Temperature => "°C",
            Quantity::Velocity => "m/s",
            Quantity::Ratio | Quantity::Count => "-",
        }
    }
}

/// A unit: its quantity, symbol and exact conversion to the internal unit
/// (`si = value × scale / divisor + offset`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Unit {
    /// The canonical symbol (`mm`).
    pub symbol: &'static str,
    /// What it measures.
    pub quantity: Quantity,
    /// Multiplier, a decimal text.
    pub scale: &'static str,
    /// Integer divisor.
    pub divisor: u64,
    /// Offset added after scaling, a decimal text.
    pub offset: &'static str,
    /// Spellings that mean this unit (compared without case).
    pub spellings: &'static [&'static str],
}

impl Unit {
    /// The exact conversion to the internal unit.
    pub fn conversion(&self) -> super::decimal::Conversion {
        super::decimal::Conversion::new(self.scale, self.divisor, self.offset).expect("the unit table holds decimal texts")
    }

    /// True when values are taken as written.
    pub fn is_si(&self) -> bool {
        self.scale == "1" && self.divisor == 1 && self.offset == "0"
    }

    /// How a conversion reads in a record: `× 1e-3`, `− 273.15`, `× 9.80665`.
    pub fn describe(&self) -> String {
        if self.is_si() {
            return String::new();
        }
        let mut s = String::new();
        if self.scale != "1" || self.divisor != 1 {
            s.push_str(&format!("× {}", self.scale));
            if self.divisor != 1 {
                s.push_str(&format!(" / {}", self.divisor));
            }
        }
        if self.offset != "0" {
            if !s.is_empty() {
                s.push(' ');
            }
            match self.offset.strip_prefix('-') {
                Some(o) => s.push_str(&format!("− {o}")),
                None => s.push_str(&format!("+ {}", self.offset)),
            }
        }
        s
    }
}

const fn unit(symbol: &'static str, quantity: Quantity, scale: &'static str, spellings: &'static [&'static str]) -> Unit {
    Unit { symbol, quantity, scale, divisor: 1, offset: "0", spellings }
}

/// Every unit the intake knows (module docs). No two spellings collide without case.
pub const UNITS: [Unit; 22] = [
    unit("m", Quantity::Length, "1", &["m"]),
    unit("mm", Quantity::Length, "1e-3", &["mm"]),
    unit("µm", Quantity::Length, "1e-6", &["µm", "um", "μm", "micron", "microns"]),
    unit("N", Quantity::Force, "1", &["n"]),
    unit("kN", Quantity::Force, "1e3", &["kn"]),
    unit("mN", Quantity::Force, "1e-3", &["mn"]),
    unit("kgf", Quantity::Force, "9.80665", &["kgf", "kp"]),
    unit("lbf", Quantity::Force, "4.4482216152605", &["lbf"]),
    unit("Pa", Quantity::Stress, "1", &["pa"]),
    unit("kPa", Quantity::Stress, "1e3", &["kpa"]),
    unit("MPa", Quantity::Stress, "1e6", &["mpa", "n/mm²", "n/mm2", "n/mm^2", "mn/m²", "mn/m2", "mn/m^2"]),
    unit("GPa", Quantity::Stress, "1e9", &["gpa"]),
    unit("kgf/mm²", Quantity::Stress, "9.80665e6", &["kgf/mm²", "kgf/mm2", "kgf/mm^2", "kp/mm²", "kp/mm2", "kp/mm^2"]),
    Unit { symbol: "psi", quantity: Quantity::Stress, scale: "4.4482216152605e8", divisor: 64516, offset: "0", spellings: &["psi", "lbf/in²", "lbf/in2", "lbf/in^2", "lb/in²", "lb/in2", "lb/in^2"] },
    Unit { symbol: "ksi", quantity: Quantity::Stress, scale: "4.4482216152605e11", divisor: 64516, offset: "0", spellings: &["ksi"] },
    unit("°C", Quantity::Temperature, "1", &["°c", "ºc", "degc", "c", "celsius", "deg c", "° c"]),
    Unit { symbol: "K", quantity: Quantity::Temperature, scale: "1", divisor: 1, offset: "-273.15", spellings: &["k", "kelvin"] },
    unit("m/s", Quantity::Velocity, "1", &["m/s", "m s-1", "m·s⁻¹", "m_s"]),
    unit("mm/s", Quantity::Velocity, "1e-3", &["mm/s", "mm s-1", "mm_s"]),
    unit("-", Quantity::Ratio, "1", &["-", "1", ""]),
    unit("%", Quantity::Ratio, "1e-2", &["%"]),
    unit("-", Quantity::Count, "1", &["-", "1", ""]),
];

/// The units spelled `text` (without case; surrounding blanks ignored): one per quantity that
/// uses the spelling (`-` is both a ratio and a count).
pub fn lookup(text: &str) -> Vec<&'static Unit> {
    let t = text.trim().to_lowercase();
    UNITS.iter().filter(|u| u.spellings.iter().any(|s| *s == t)).collect()
}

/// The unit `text` of quantity `q`, if the grammar has one.
pub fn unit_of(q: Quantity, text: &str) -> Option<&'static Unit> {
    lookup(text).into_iter().find(|u| u.quantity == q)
}

/// The internal unit of `q`.
pub fn si_unit(q: Quantity) -> &'static Unit {
    UNITS.iter().find(|u| u.quantity == q && u.is_si()).expect("every quantity has its internal unit")
}

/// A header split into its name and the unit it states (module docs: the three forms).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Header {
    /// The header as written (trimmed).
    pub text: String,
    /// The name without the unit (`D`, `diameter`).
    pub name: String,
    /// The unit as written (`mm`), if the header states one.
    pub unit: Option<String>,
}

/// Splits a header into name and unit. A bracket or slash form always counts as a unit (so a
/// wrong unit is reported, not taken as part of the name); a snake-case suffix counts only when
/// it is a known unit spelling (`particle_id` keeps its name).
pub fn parse_header(text: &str) -> Header {
    let t = text.trim();
    let plain = |name: &str| Header { text: t.to_string(), name: name.trim().to_string(), unit: None };
    for (open, close) in [('[', ']'), ('(', ')')] {
        if let Some(body) = t.strip_suffix(close)
            && let Some(k) = body.rfind(open)
            && !body[..k].trim().is_empty()
        {
            return Header { text: t.to_string(), name: body[..k].trim().trim_end_matches([',', '/', ' ']).trim().to_string(), unit: Some(body[k + 1..].trim().to_string()) };
        }
    }
    if let Some(k) = t.find('/') {
        let (name, rest) = (t[..k].trim(), t[k + 1..].trim());
        let rest = rest.strip_prefix('(').and_then(|r| r.strip_suffix(')')).unwrap_or(rest);
        if !name.is_empty() && !lookup(rest).is_empty() {
            return Header { text: t.to_string(), name: name.to_string(), unit: Some(rest.to_string()) };
        }
    }
    // Snake-case suffix: the last two segments (`m_s`) or the last one.
    let parts: Vec<&str> = t.split('_').collect();
    for take in [2, 1] {
        if parts.len() > take {
            let suffix = parts[parts.len() - take..].join("_");
            let found = lookup(&suffix);
            if !suffix.is_empty() && !found.is_empty() && found.iter().all(|u| !u.symbol.starts_with('-')) {
                return Header { text: t.to_string(), name: parts[..parts.len() - take].join("_"), unit: Some(suffix) };
            }
        }
    }
    plain(t)
}

/// A name reduced to what tells names apart: lower case, without blanks, `_`, `-`, `.`.
pub fn fold(name: &str) -> String {
    name.chars().filter(|c| !matches!(c, ' ' | '_' | '-' | '.')).flat_map(char::to_lowercase).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn split(h: &str) -> (String, Option<String>) {
        let p = parse_header(h);
        (p.name, p.unit)
    }

    #[test]
    fn headers_state_units_in_three_forms() {
        let s = |a: &str, b: Option<&str>| (a.to_string(), b.map(str::to_string));
        assert_eq!(split("D [mm]"), s("D", Some("mm")));
        assert_eq!(split("d (µm)"), s("d", Some("µm")));
        assert_eq!(split("F_max (kN)"), s("F_max", Some("kN")));
        assert_eq!(split(" T [°C] "), s("T", Some("°C")));
        assert_eq!(split("Fmax [N]"), s("Fmax", Some("N")));
        assert_eq!(split("d/mm"), s("d", Some("mm")));
        assert_eq!(split("v/(m/s)"), s("v", Some("m/s")));
        assert_eq!(split("diameter_m"), s("diameter", Some("m")));
        assert_eq!(split("crush_force_n"), s("crush_force", Some("n")));
        assert_eq!(split("temperature_c"), s("temperature", Some("c")));
        assert_eq!(split("temperature_k"), s("temperature", Some("k")));
        assert_eq!(split("v_normal_m_s"), s("v_normal", Some("m_s")));
        assert_eq!(split("diameter_mm"), s("diameter", Some("mm")));
        // No unit: the name stays whole.
        assert_eq!(split("particle_id"), s("particle_id", None));
        assert_eq!(split("roundness"), s("roundness", None));
        assert_eq!(split("B/L"), s("B/L", None));
        assert_eq!(split("F_max"), s("F_max", None));
        // A bracket always states a unit, even a wrong one.
        assert_eq!(split("D [N]"), s("D", Some("N")));
    }

    #[test]
    fn every_unit_belongs_to_its_quantity_and_spellings_do_not_collide() {
        assert_eq!(unit_of(Quantity::Force, "KGF").unwrap().symbol, "kgf");
        assert_eq!(unit_of(Quantity::Stress, "MPa").unwrap().symbol, "MPa");
        assert_eq!(unit_of(Quantity::Stress, "N/mm²").unwrap().symbol, "MPa");
        // The stress units of older strength tables.
        assert_eq!(unit_of(Quantity::Stress, "MN/m²").unwrap().symbol, "MPa");
        assert_eq!(unit_of(Quantity::Stress, "kp/mm2").unwrap().symbol, "kgf/mm²");
        assert_eq!(unit_of(Quantity::Stress, "lbf/in²").unwrap().symbol, "psi");
        assert_eq!(unit_of(Quantity::Stress, "kgf/mm²").unwrap().conversion().apply("1.5"), Some(14.709975e6));
        assert_eq!(unit_of(Quantity::Length, "um").unwrap().symbol, "µm");
        assert_eq!(unit_of(Quantity::Temperature, "K").unwrap().offset, "-273.15");
        assert!(unit_of(Quantity::Length, "N").is_none());
        for a in &UNITS {
            for s in a.spellings {
                assert_eq!(s.to_lowercase(), *s, "spellings are lower case: {s}");
                for b in lookup(s) {
                    assert!(b == a || b.quantity != a.quantity, "{s} means two units of one quantity");
                }
            }
            assert!(a.conversion().apply("1").is_some());
        }
        assert_eq!(si_unit(Quantity::Temperature).symbol, "°C");
        assert_eq!(unit_of(Quantity::Force, "kN").unwrap().describe(), "× 1e3");
        assert_eq!(unit_of(Quantity::Temperature, "K").unwrap().describe(), "− 273.15");
    }
}
