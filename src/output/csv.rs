//! Minimal CSV writer for numeric tables (time series, convergence logs).

use std::fmt::Write as _;
use std::path::Path;

use super::atomic::write_atomic;
use super::OutputError;

/// Serializes a numeric table: one header line, then one line per row.
///
/// Numbers use Rust's shortest round-trip formatting, so parsing the text
/// gives back the identical `f64`. Plain notation is used where it stays
/// short, exponent notation otherwise (`{}` alone would print 1e-300 with
/// 300 digits). Non-finite values are written as `NaN`, `inf`, `-inf`.
/// Header names containing `,`, `"` or line breaks are quoted (RFC 4180).
///
/// Rows are written as given; [`write_csv`] rejects ragged tables.
pub fn csv_bytes(header: &[&str], rows: &[Vec<f64>]) -> Vec<u8> {
    let mut s = String::new();
    for (i, h) in header.iter().enumerate() {
        if i > 0 {
            s.push(',');
        }
        if h.contains([',', '"', '\n', '\r']) {
            let _ = write!(s, "\"{}\"", h.replace('"', "\"\""));
        } else {
            s.push_str(h);
        }
    }
    s.push('\n');
    for row in rows {
        for (i, &v) in row.iter().enumerate() {
            if i > 0 {
                s.push(',');
            }
            write_number(&mut s, v);
        }
        s.push('\n');
    }
    s.into_bytes()
}

/// Writes a CSV table atomically.
///
/// Errors: [`OutputError::Shape`] (field `"row {i}"`) if a row's length differs
/// from the header's, [`OutputError::Io`] if the file cannot be written.
pub fn write_csv(path: &Path, header: &[&str], rows: &[Vec<f64>]) -> Result<(), OutputError> {
    if let Some((i, row)) = rows.iter().enumerate().find(|(_, r)| r.len() != header.len()) {
        return Err(OutputError::Shape {
            field: format!("row {i}"),
            expected: header.len(),
            found: row.len(),
        });
    }
    write_atomic(path, &csv_bytes(header, rows)).map_err(OutputError::io(path))
}

fn write_number(s: &mut String, v: f64) {
    let a = v.abs();
    let _ = if a == 0.0 || !a.is_finite() || (1e-5..1e16).contains(&a) {
        write!(s, "{v}")
    } else {
        write!(s, "{v:e}")
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
        let mut lines = text.lines();
        let header = lines.next().unwrap().split(',').map(String::from).collect();
        let rows = lines
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect();
        (header, rows)
    }

    #[test]
    fn table_round_trips_exactly() {
        let header = ["t", "energy", "max_gap"];
        let rows = vec![
            vec![0.0, 1.0 / 3.0, -0.0],
            vec![0.1, 2.5e17, 1e-300],
            vec![1e16, -123.456, 6.02214076e23],
            vec![f64::MIN_POSITIVE, f64::MAX, 9.999e-6],
        ];
        let text = String::from_utf8(csv_bytes(&header, &rows)).unwrap();
        assert!(text.starts_with("t,energy,max_gap\n0,"), "{text}");
        assert!(text.lines().all(|l| l.len() < 80), "{text}");
        let (h, back) = parse(&text);
        assert_eq!(h, header);
        let bits =
            |m: &[Vec<f64>]| -> Vec<Vec<u64>> { m.iter().map(|r| r.iter().map(|v| v.to_bits()).collect()).collect() };
        assert_eq!(bits(&back), bits(&rows));
    }

    #[test]
    fn non_finite_values_parse_back() {
        let text = String::from_utf8(csv_bytes(&["a"], &[vec![f64::NAN], vec![f64::NEG_INFINITY]])).unwrap();
        assert_eq!(text, "a\nNaN\n-inf\n");
        let (_, back) = parse(&text);
        assert!(back[0][0].is_nan());
        assert_eq!(back[1][0], f64::NEG_INFINITY);
    }

    #[test]
    fn awkward_header_names_are_quoted() {
        let text = String::from_utf8(csv_bytes(&["x", "a,b", "say \"hi\""], &[])).unwrap();
        assert_eq!(text, "x,\"a,b\",\"say \"\"hi\"\"\"\n");
    }

    #[test]
    fn ragged_rows_are_rejected_and_nothing_is_written() {
        let dir = std::env::temp_dir().join(format!("thermocontact-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("log.csv");
        let err = write_csv(&path, &["a", "b"], &[vec![1.0, 2.0], vec![3.0]]).unwrap_err();
        assert!(
            matches!(&err, OutputError::Shape { field, expected: 2, found: 1 } if field == "row 1"),
            "{err:?}"
        );
        assert!(!path.exists());
        write_csv(&path, &["a", "b"], &[vec![1.0, 2.0]]).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "a,b\n1,2\n");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
