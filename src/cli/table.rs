//! Aligned terminal tables (comfy-table without borders): the run summary, `check` and
//! `bench` print their columns through this one helper.

use comfy_table::{CellAlignment, ContentArrangement, Table, presets};

/// How a column's cells line up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Align {
    Left,
    Right,
}

/// A borderless table, columns two spaces apart.
pub struct Columns {
    table: Table,
    align: Vec<Align>,
}

/// A table with the given header (all empty: no header line) and column alignments.
pub fn new(header: &[&str], align: &[Align]) -> Columns {
    debug_assert_eq!(header.len(), align.len());
    let mut table = Table::new();
    table
        .load_style(presets::NOTHING)
        .set_content_arrangement(ContentArrangement::Disabled);
    if header.iter().any(|h| !h.is_empty()) {
        table.set_header(header.to_vec());
    }
    Columns {
        table,
        align: align.to_vec(),
    }
}

impl Columns {
    /// Adds a row; control characters in a cell (a name from a file) are shown
    /// escaped, never sent to the terminal.
    pub fn add_row(&mut self, cells: Vec<String>) -> &mut Self {
        debug_assert_eq!(cells.len(), self.align.len());
        let cells: Vec<String> = cells
            .into_iter()
            .map(|c| orbitlash::units::shown(&c).into_owned())
            .collect();
        self.table.add_row(cells);
        self
    }
}

/// A number's cell with `decimals` digits after the point, or "–" when it is not a
/// number (a window that saw no step, a case with no valid mesh).
pub fn number(v: f64, decimals: usize) -> String {
    if v.is_finite() {
        format!("{v:.decimals$}")
    } else {
        "–".to_string()
    }
}

/// The table's lines, each after `indent` and without trailing blanks.
pub fn render(t: &Columns, indent: &str) -> String {
    let mut table = t.table.clone();
    for (i, a) in t.align.iter().enumerate() {
        if let Some(c) = table.column_mut(i) {
            c.set_cell_alignment(match a {
                Align::Left => CellAlignment::Left,
                Align::Right => CellAlignment::Right,
            });
            c.set_padding((0, 2));
        }
    }
    let mut o = String::new();
    for line in table.lines() {
        o.push_str(indent);
        o.push_str(line.trim_end());
        o.push('\n');
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cli_table_aligns_columns_two_spaces_apart() {
        let mut t = new(&["node", "min °C"], &[Align::Left, Align::Right]);
        t.add_row(vec!["housing".to_string(), "-24.74".to_string()]);
        t.add_row(vec!["gear1.r0".to_string(), "1.00".to_string()]);
        let text = render(&t, "  ");
        assert_eq!(
            text, "  node      min °C\n  housing   -24.74\n  gear1.r0    1.00\n",
            "{text}"
        );
    }
}

#[cfg(test)]
mod headless {
    use super::*;

    #[test]
    fn cli_table_without_header_still_aligns() {
        let mut t = new(&["", ""], &[Align::Left, Align::Right]);
        t.add_row(vec!["stored".to_string(), "1.5".to_string()]);
        t.add_row(vec!["error".to_string(), "-10.25".to_string()]);
        assert_eq!(render(&t, ""), "stored     1.5\nerror   -10.25\n");
    }
}
