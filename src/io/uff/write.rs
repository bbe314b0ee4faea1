//! Writing universal files: units (164, SI), the measurement points as
//! nodes (15) and a trace line through them (82), FRFs with their
//! coherences (58, ASCII, complex double precision) and mode shapes at the
//! nodes (55), in the fixed-width records pyuff and modal-testing software
//! read (`E13.5` for single precision fields, `E20.12` for double).

use super::UffPoint;
use crate::io::frf_json::FrfFile;
use splinewatch_core::c64;
use splinewatch_core::response::frf::Quantity;
use std::fmt::Write;

/// A mode shape at the points (one value per point, in the points' order).
#[derive(Debug, Clone, PartialEq)]
pub struct UffMode {
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    pub shape: Vec<c64>,
}

/// A universal file being written; [`UffWriter::finish`] gives its text.
pub struct UffWriter {
    text: String,
}

impl Default for UffWriter {
    fn default() -> Self {
        Self::new()
    }
}

/// `v` as a Fortran `Ew.d` field: sign, one digit, `digits` decimals, a
/// signed two-digit (or longer) exponent, right-aligned in `width`.
fn e(v: f64, width: usize, digits: usize) -> String {
    let s = format!("{:.*E}", digits, v);
    let (mantissa, exponent) = s.split_once('E').expect("E format");
    let exponent: i32 = exponent.parse().expect("an exponent");
    let sign = if exponent < 0 { '-' } else { '+' };
    format!("{:>width$}", format!("{mantissa}E{sign}{:02}", exponent.abs()))
}

/// A record of `%-80s`.
fn line80(text: &str) -> String {
    let t: String = text.chars().take(80).collect();
    format!("{t:<80}\n")
}

impl UffWriter {
    /// A file that starts with dataset 164: SI units (m, N, °C, s).
    pub fn new() -> Self {
        let mut text = String::new();
        text.push_str("    -1\n   164\n");
        let _ = writeln!(text, "{:>10}{:>20}{:>10}", 1, "SI - mks (Newton)", 2);
        let _ = writeln!(text, "{}{}{}", e(1.0, 25, 16), e(1.0, 25, 16), e(1.0, 25, 16));
        let _ = writeln!(text, "{}", e(273.15, 25, 16));
        text.push_str("    -1\n");
        Self { text }
    }

    /// Dataset 15: one node per distinct node number, at its first point.
    pub fn nodes(&mut self, points: &[UffPoint]) {
        self.text.push_str("    -1\n    15\n");
        let mut seen = Vec::new();
        for p in points {
            if seen.contains(&p.node) {
                continue;
            }
            seen.push(p.node);
            let [x, y, z] = p.position;
            let _ = writeln!(
                self.text,
                "{:>10}{:>10}{:>10}{:>10}{}{}{}",
                p.node,
                0,
                0,
                0,
                e(x, 13, 5),
                e(y, 13, 5),
                e(z, 13, 5)
            );
        }
        self.text.push_str("    -1\n");
    }

    /// Dataset 82: trace line `number` through the points' nodes in order.
    pub fn trace_line(&mut self, number: i64, id: &str, points: &[UffPoint]) {
        self.text.push_str("    -1\n    82\n");
        let _ = writeln!(self.text, "{number:>10}{:>10}{:>10}", points.len(), 1);
        self.text.push_str(&line80(id));
        for chunk in points.chunks(8) {
            let row: String = chunk.iter().map(|p| format!("{:>10}", p.node)).collect();
            let _ = writeln!(self.text, "{row}");
        }
        self.text.push_str("    -1\n");
    }

    /// Datasets 58: every FRF of `frf` (function type 4, complex double)
    /// and its coherence (function type 6) when it has one. `what` heads
    /// the ID lines (e.g. "measured", "model").
    pub fn frfs(&mut self, frf: &FrfFile, points: &[UffPoint], what: &str) -> Result<(), String> {
        let point = |name: &str| {
            points
                .iter()
                .find(|p| p.name == name)
                .ok_or_else(|| format!("FRF sensor {name:?} is not a point of the file"))
        };
        let f = &frf.frequency_hz;
        let even = f.len() > 1
            && f.windows(2)
                .all(|w| ((w[1] - w[0]) - (f[1] - f[0])).abs() <= 1e-9 * f[1].abs());
        for entry in &frf.frfs {
            let (out, inp) = (point(&entry.output)?, point(&entry.input)?);
            let header = Header58 {
                id: format!("{what} {} / {}", entry.output, entry.input),
                response: (out.node, out.direction_code()?),
                reference: (inp.node, inp.direction_code()?),
                frequency_hz: f,
                even,
            };
            let values: Vec<(f64, f64)> = entry.re.iter().zip(&entry.im).map(|(&r, &i)| (r, i)).collect();
            self.dataset58(&header, 4, Some(frf.quantity), &values);
            if let Some(c) = &entry.coherence {
                let values: Vec<(f64, f64)> = c.iter().map(|&v| (v, 0.0)).collect();
                let header = Header58 {
                    id: format!("{what} coherence {} / {}", entry.output, entry.input),
                    ..header
                };
                self.dataset58(&header, 6, None, &values);
            }
        }
        Ok(())
    }

    /// One dataset 58: `function` 4 (FRF of `quantity`, complex) or 6
    /// (coherence, real).
    fn dataset58(&mut self, h: &Header58<'_>, function: i64, quantity: Option<Quantity>, values: &[(f64, f64)]) {
        let t = &mut self.text;
        t.push_str("    -1\n    58\n");
        t.push_str(&line80(&h.id));
        t.push_str(&line80("splinewatch"));
        t.push_str(&line80(""));
        t.push_str(&line80(""));
        t.push_str(&line80(""));
        let _ = writeln!(
            t,
            "{function:>5}{:>10}{:>5}{:>10} {:<10}{:>10}{:>4} {:<10}{:>10}{:>4}",
            0, 0, 0, "NONE", h.response.0, h.response.1, "NONE", h.reference.0, h.reference.1
        );
        let complex = quantity.is_some();
        let (first, step) = match (h.even, h.frequency_hz) {
            (true, [a, b, ..]) => (*a, b - a),
            _ => (0.0, 0.0),
        };
        let _ = writeln!(
            t,
            "{:>10}{:>10}{:>10}{}{}{}",
            if complex { 6 } else { 4 },
            values.len(),
            i64::from(h.even),
            e(first, 13, 5),
            e(step, 13, 5),
            e(0.0, 13, 5)
        );
        // Records 8–11: abscissa (frequency, Hz), ordinate, denominator, z axis.
        let axis = |t: &mut String, kind: i64, length: i64, force: i64, label: &str, units: &str| {
            let _ = writeln!(t, "{kind:>10}{length:>5}{force:>5}{:>5} {label:<20} {units:<20}", 0);
        };
        axis(t, 18, 0, 0, "Frequency", "Hz");
        match quantity {
            Some(q) => {
                let (kind, label, units) = match q {
                    Quantity::Receptance => (8, "Displacement", "m"),
                    Quantity::Mobility => (11, "Velocity", "m/s"),
                    Quantity::Accelerance => (12, "Acceleration", "m/s^2"),
                };
                axis(t, kind, 1, 0, label, units);
                axis(t, 13, 0, 1, "Force", "N");
            }
            None => {
                axis(t, 0, 0, 0, "Coherence", "");
                axis(t, 0, 0, 0, "NONE", "");
            }
        }
        axis(t, 0, 0, 0, "NONE", "");
        let mut fields = Vec::with_capacity(values.len() * 3);
        for (k, &(re, im)) in values.iter().enumerate() {
            if !h.even {
                fields.push(h.frequency_hz[k]);
            }
            fields.push(re);
            if complex {
                fields.push(im);
            }
        }
        for chunk in fields.chunks(4) {
            let row: String = chunk.iter().map(|&v| e(v, 20, 12)).collect();
            let _ = writeln!(t, "{row}");
        }
        t.push_str("    -1\n");
    }

    /// Datasets 55: real normal modes (analysis type 2: frequency, unit
    /// modal mass, viscous damping ratio; shapes' real parts).
    pub fn normal_modes(&mut self, modes: &[UffMode], points: &[UffPoint], id: &str) {
        for (n, mode) in modes.iter().enumerate() {
            self.dataset55_head(id, 2, false);
            let _ = writeln!(self.text, "{:>10}{:>10}{:>10}{:>10}", 2, 4, 1, n + 1);
            let _ = writeln!(
                self.text,
                "{}{}{}{}",
                e(mode.frequency_hz, 13, 5),
                e(1.0, 13, 5),
                e(mode.damping_ratio, 13, 5),
                e(0.0, 13, 5)
            );
            for (node, [x, y, z]) in node_vectors(mode, points) {
                let _ = writeln!(
                    self.text,
                    "{node:>10}\n{}{}{}",
                    e(x.re, 13, 5),
                    e(y.re, 13, 5),
                    e(z.re, 13, 5)
                );
            }
            self.text.push_str("    -1\n");
        }
    }

    /// Datasets 55: complex modes (analysis type 3, the eigenvalue
    /// `λ = −ζω + iω√(1−ζ²)`), e.g. identified output-only.
    pub fn complex_modes(&mut self, modes: &[UffMode], points: &[UffPoint], id: &str) {
        for (n, mode) in modes.iter().enumerate() {
            self.dataset55_head(id, 3, true);
            let omega = 2.0 * std::f64::consts::PI * mode.frequency_hz;
            let zeta = mode.damping_ratio.clamp(0.0, 1.0);
            let (re, im) = (-zeta * omega, omega * (1.0 - zeta * zeta).sqrt());
            let _ = writeln!(self.text, "{:>10}{:>10}{:>10}{:>10}", 2, 6, 1, n + 1);
            let _ = writeln!(
                self.text,
                "{}{}{}{}{}{}",
                e(re, 13, 5),
                e(im, 13, 5),
                e(0.0, 13, 5),
                e(0.0, 13, 5),
                e(0.0, 13, 5),
                e(0.0, 13, 5)
            );
            for (node, [x, y, z]) in node_vectors(mode, points) {
                let _ = writeln!(
                    self.text,
                    "{node:>10}\n{}{}{}{}{}{}",
                    e(x.re, 13, 5),
                    e(x.im, 13, 5),
                    e(y.re, 13, 5),
                    e(y.im, 13, 5),
                    e(z.re, 13, 5),
                    e(z.im, 13, 5)
                );
            }
            self.text.push_str("    -1\n");
        }
    }

    /// Records 1–6 of a dataset 55: ID lines, then model type 1
    /// (structural), `analysis`, 3 dofs per node, data type 8 (displacement),
    /// real (2) or complex (5) values, 3 per node.
    fn dataset55_head(&mut self, id: &str, analysis: i64, complex: bool) {
        self.text.push_str("    -1\n    55\n");
        self.text.push_str(&line80(id));
        for _ in 0..4 {
            self.text.push_str(&line80("NONE"));
        }
        let _ = writeln!(
            self.text,
            "{:>10}{analysis:>10}{:>10}{:>10}{:>10}{:>10}",
            1,
            2,
            8,
            if complex { 5 } else { 2 },
            3
        );
    }

    pub fn finish(self) -> String {
        self.text
    }
}

struct Header58<'a> {
    id: String,
    response: (i64, i64),
    reference: (i64, i64),
    frequency_hz: &'a [f64],
    even: bool,
}

/// A mode's translation vector at each distinct node: every point's value
/// along its direction, summed over the points of a node.
fn node_vectors(mode: &UffMode, points: &[UffPoint]) -> Vec<(i64, [c64; 3])> {
    let mut out: Vec<(i64, [c64; 3])> = Vec::new();
    for (p, &value) in points.iter().zip(&mode.shape) {
        let k = match out.iter().position(|(n, _)| *n == p.node) {
            Some(k) => k,
            None => {
                out.push((p.node, [c64::new(0.0, 0.0); 3]));
                out.len() - 1
            }
        };
        for (axis, d) in p.direction().iter().enumerate() {
            out[k].1[axis] += value * *d;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fortran_fields_have_signed_two_digit_exponents() {
        assert_eq!(e(1.0, 13, 5), "  1.00000E+00");
        assert_eq!(e(-0.000123456, 13, 5), " -1.23456E-04");
        assert_eq!(e(6.02e23, 20, 12), "  6.020000000000E+23");
        assert_eq!(e(0.0, 13, 5), "  0.00000E+00");
    }
}
