//! Scenario files (TOML): the text read into a [`ScenarioSpec`], compiled into a
//! [`Scenario`], and errors that name the file, the line, the column and the key.
//!
//! Every key is documented in `scenarios/README.md`; keep the two in step.

use std::path::Path;

use crate::spec::scenario::Scenario;
use crate::spec::{KeyPath, ScenarioSpec, Seg, SpecError, compile};

/// The reference scenario, embedded in the binary.
pub const REFERENCE_HINGE_TOML: &str = include_str!("../../scenarios/reference-hinge.toml");
pub const REFERENCE_HINGE_NAME: &str = "reference-hinge";

#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    #[error("cannot read scenario {file}")]
    Read {
        file: String,
        source: std::io::Error,
    },
    #[error("{file}: {message}")]
    Syntax { file: String, message: String },
    #[error("{file}:{line}:{column}: `{key}`: {message}")]
    Invalid {
        file: String,
        line: usize,
        column: usize,
        key: String,
        message: String,
    },
}

/// Reads a scenario file into its spec, without validating it beyond the schema:
/// (spec, text).
pub fn read_spec_file(path: &Path) -> Result<(ScenarioSpec, String), ScenarioError> {
    let file = path.display().to_string();
    let text = super::output::check_input(path)
        .and_then(|()| std::fs::read_to_string(path))
        .map_err(|source| ScenarioError::Read {
            file: file.clone(),
            source,
        })?;
    Ok((parse_spec(&text, &file)?, text))
}

/// Reads and validates a scenario file.
pub fn load_file(path: &Path) -> Result<(Scenario, String), ScenarioError> {
    let (spec, text) = read_spec_file(path)?;
    let scenario = compile(spec).map_err(|e| located(&text, &path.display().to_string(), e))?;
    Ok((scenario, text))
}

/// Parses and validates scenario text; `file` names it in errors.
pub fn parse(text: &str, file: &str) -> Result<Scenario, ScenarioError> {
    let spec = parse_spec(text, file)?;
    compile(spec).map_err(|e| located(text, file, e))
}

/// The error of `e` at its key's place in `text`: the deepest part of the key path
/// present in the file.
pub fn located(text: &str, file: &str, e: SpecError) -> ScenarioError {
    let line_of = |offset: usize| text[..offset.min(text.len())].matches('\n').count() + 1;
    let offset = locate(text, &e.key).unwrap_or(0);
    let before = &text[..offset.min(text.len())];
    let message = match e.also.as_ref().and_then(|k| Some((k, locate(text, k)?))) {
        Some((k, at)) => format!("{} (also `{k}` at line {})", e.message, line_of(at)),
        None => e.message,
    };
    ScenarioError::Invalid {
        file: file.to_string(),
        line: line_of(offset),
        column: before.len() - before.rfind('\n').map_or(0, |p| p + 1) + 1,
        key: e.key.to_string(),
        message,
    }
}

/// Reads scenario text into its spec (no validation beyond the schema).
pub fn parse_spec(text: &str, file: &str) -> Result<ScenarioSpec, ScenarioError> {
    toml::from_str(text).map_err(|e| {
        let excerpt = shorten_excerpt(e.to_string().trim_end());
        // A schema error (unknown key, wrong type, missing key) names its key path on
        // the first line, like every other error; a malformed file names the line.
        match e
            .span()
            .and_then(|s| Some((s.start, key_path_at(text, s.start)?)))
        {
            Some((offset, key)) => {
                let before = &text[..offset.min(text.len())];
                ScenarioError::Invalid {
                    file: file.to_string(),
                    line: before.matches('\n').count() + 1,
                    column: before.len() - before.rfind('\n').map_or(0, |p| p + 1) + 1,
                    key,
                    message: format!("{}\n{excerpt}", clip_line(e.message().trim_end())),
                }
            }
            None => ScenarioError::Syntax {
                file: file.to_string(),
                message: excerpt,
            },
        }
    })
}

/// A message line cut to 4 × [`EXCERPT_HALF_WIDTH`] characters, "…" where it was cut
/// (a type error quotes the value, which may be a whole long line).
fn clip_line(line: &str) -> String {
    let max = 4 * EXCERPT_HALF_WIDTH;
    if line.chars().count() <= max {
        line.to_string()
    } else {
        format!("{}…", line.chars().take(max).collect::<String>())
    }
}

/// Characters of a source line shown either side of the error's column.
const EXCERPT_HALF_WIDTH: usize = 60;

/// A parse error's excerpt (`N | source line` over `  | ^` at the column) with a long
/// source line cut to [`EXCERPT_HALF_WIDTH`] characters either side of the caret, "…"
/// where it was cut: a 400 000-character line was printed whole.
fn shorten_excerpt(excerpt: &str) -> String {
    let lines: Vec<&str> = excerpt.lines().collect();
    // the caret's line and the column of its caret, in characters after "| "
    let caret = lines.iter().enumerate().find_map(|(i, l)| {
        let (gutter, rest) = l.split_once("| ")?;
        (gutter.trim().is_empty() && rest.trim_start().starts_with('^'))
            .then(|| (i, rest.chars().take_while(|c| *c == ' ').count()))
    });
    let Some((at, col)) = caret else {
        return excerpt
            .lines()
            .map(clip_line)
            .collect::<Vec<_>>()
            .join("\n");
    };
    let from = col.saturating_sub(EXCERPT_HALF_WIDTH);
    let to = col + EXCERPT_HALF_WIDTH;
    let long = at > 0
        && lines[at - 1]
            .split_once("| ")
            .is_some_and(|(_, r)| r.chars().count() > 2 * EXCERPT_HALF_WIDTH + 1);
    let mut out = Vec::with_capacity(lines.len());
    for (i, l) in lines.iter().enumerate() {
        // the source line (just above the caret's) and the caret's, when long
        let cut_here = (i == at || i + 1 == at) && long;
        let Some((gutter, rest)) = l.split_once("| ").filter(|_| cut_here) else {
            // the message's lines (a type error quotes the whole value)
            out.push(clip_line(l));
            continue;
        };
        let n = rest.chars().count();
        let cut: String = rest.chars().skip(from).take(to - from).collect();
        let (head, tail) = match (i == at, from > 0, to < n) {
            (true, true, _) => (" ", ""), // the caret keeps its place under the "…"
            (true, false, _) => ("", ""),
            (false, h, t) => (if h { "…" } else { "" }, if t { "…" } else { "" }),
        };
        out.push(format!(
            "{gutter}| {head}{}{tail}",
            cut.trim_end_matches(' ')
        ));
    }
    out.join("\n")
}

/// The embedded reference scenario.
pub fn reference() -> Scenario {
    parse(REFERENCE_HINGE_TOML, "<embedded reference-hinge.toml>")
        .expect("embedded reference scenario is valid")
}

/// The key path (`node[2].capacitance_j_per_k`) of the innermost key, value or table
/// of `text` whose span holds `offset`; `None` when the text does not parse.
fn key_path_at(text: &str, offset: usize) -> Option<String> {
    use toml_edit::{Item, Table, Value};
    type Best = Option<(usize, String)>;
    fn consider(span: Option<std::ops::Range<usize>>, path: &str, offset: usize, best: &mut Best) {
        if let Some(s) = span
            && s.contains(&offset)
            && !path.is_empty()
            && best.as_ref().is_none_or(|(len, _)| s.len() <= *len)
        {
            *best = Some((s.len(), path.to_string()));
        }
    }
    fn join(path: &str, key: &str) -> String {
        if path.is_empty() {
            key.to_string()
        } else {
            format!("{path}.{key}")
        }
    }
    fn value(v: &Value, path: &str, offset: usize, best: &mut Best) {
        consider(v.span(), path, offset, best);
        match v {
            Value::InlineTable(t) => {
                for (k, x) in t.iter() {
                    let p = join(path, k);
                    if let Some((key, _)) = t.get_key_value(k) {
                        consider(key.span(), &p, offset, best);
                    }
                    value(x, &p, offset, best);
                }
            }
            Value::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    value(x, &format!("{path}[{i}]"), offset, best);
                }
            }
            _ => {}
        }
    }
    fn table(t: &Table, path: &str, offset: usize, best: &mut Best) {
        consider(t.span(), path, offset, best);
        for (k, x) in t.iter() {
            let p = join(path, k);
            if let Some((key, _)) = t.get_key_value(k) {
                consider(key.span(), &p, offset, best);
            }
            item(x, &p, offset, best);
        }
    }
    fn item(x: &Item, path: &str, offset: usize, best: &mut Best) {
        match x {
            Item::Table(t) => table(t, path, offset, best),
            Item::ArrayOfTables(a) => {
                for (i, t) in a.iter().enumerate() {
                    let p = match element_key(path, i, t) {
                        Some(k) => format!("{path}.{}", crate::spec::keys::quote_key(&k)),
                        None => format!("{path}[{i}]"),
                    };
                    table(t, &p, offset, best);
                }
            }
            Item::Value(v) => value(v, path, offset, best),
            Item::None => {}
        }
    }
    let doc = toml_edit::Document::parse(text).ok()?;
    let mut best = None;
    table(doc.as_table(), "", offset, &mut best);
    best.map(|(_, p)| p)
}

/// The key of element `i` of a top-level array `section`, as `spec::keys` names it
/// (its `name`, or the default of its kind), so that schema errors name it as every
/// other error does; `None` for other arrays.
fn element_key(section: &str, i: usize, t: &toml_edit::Table) -> Option<String> {
    let field = |k: &str| t.get(k).and_then(|v| v.as_str()).map(str::to_string);
    let between = t
        .get("between")
        .and_then(|b| b.as_array())
        .and_then(|b| b.iter().map(|v| v.as_str().map(str::to_string)).collect());
    crate::spec::keys::element_key(section, i, &field, between)
}

/// Byte offset of the deepest key of `path` present in `text`.
fn locate(text: &str, path: &KeyPath) -> Option<usize> {
    let doc = toml_edit::Document::parse(text).ok()?;
    let mut item = doc.as_item();
    let mut best = None;
    for seg in &path.0 {
        let next = match seg {
            Seg::K(k) => {
                let key_span = item
                    .as_table_like()
                    .and_then(|t| t.get_key_value(k))
                    .and_then(|(key, _)| key.span());
                let next = item.get(*k);
                if let Some(nx) = next {
                    best = key_span.or_else(|| nx.span()).map(|r| r.start).or(best);
                }
                next
            }
            Seg::I(i) | Seg::E(i, _) => {
                let next = item.get(*i);
                if let Some(nx) = next {
                    best = nx.span().map(|r| r.start).or(best);
                }
                next
            }
        };
        match next {
            Some(nx) => item = nx,
            None => break,
        }
    }
    best
}

/// Why scenario text could not be edited.
#[derive(Debug, thiserror::Error)]
#[error("cannot write the edited scenario: {0}")]
pub struct EditError(String);

/// `text` (a scenario file whose spec is `from`) edited to describe `to`, keeping the
/// user's comments, order and number spellings wherever the value is unchanged: only
/// values that differ are rewritten, keys `to` lacks are removed, keys and array
/// elements it adds are inserted (new elements after the last of their kind).
/// `comment(section, index)` gives the comment put above an added element (its lines
/// without `#`), `header` the lines put at the top of the file.
pub fn edited(
    text: &str,
    from: &ScenarioSpec,
    to: &ScenarioSpec,
    header: &[String],
    comment: &dyn Fn(&str, usize) -> Option<String>,
) -> Result<String, EditError> {
    let err = |e: &dyn std::fmt::Display| EditError(e.to_string());
    let mut doc: toml_edit::DocumentMut = text.parse().map_err(|e| err(&e))?;
    let a = toml::Value::try_from(from).map_err(|e| err(&e))?;
    let b = toml::Value::try_from(to).map_err(|e| err(&e))?;
    let (Some(a), Some(b)) = (a.as_table(), b.as_table()) else {
        return Err(EditError("a scenario is a table".into()));
    };
    let mut editor = Editor {
        comment,
        next: max_position(doc.as_table()) + 1,
    };
    editor.table(doc.as_table_mut(), a, b, "")?;
    let mut top = String::new();
    for h in header {
        top.push_str(&format!("# {h}\n"));
    }
    Ok(top + &doc.to_string())
}

/// The largest document position of `t` and the tables under it.
fn max_position(t: &toml_edit::Table) -> isize {
    let mut m = t.position().unwrap_or(0);
    for (_, item) in t.iter() {
        match item {
            toml_edit::Item::Table(sub) => m = m.max(max_position(sub)),
            toml_edit::Item::ArrayOfTables(aot) => {
                for sub in aot.iter() {
                    m = m.max(max_position(sub));
                }
            }
            _ => {}
        }
    }
    m
}

/// The edit's state: the comments put above added elements, and the next document
/// position (added tables go to the end, in order).
struct Editor<'c> {
    comment: &'c dyn Fn(&str, usize) -> Option<String>,
    next: isize,
}

impl Editor<'_> {
    /// Places a new table (and its sub-tables) at the end of the document, in order.
    fn place_last(&mut self, t: &mut toml_edit::Table) {
        t.set_position(Some(self.next));
        self.next += 1;
        for (_, item) in t.iter_mut() {
            if let toml_edit::Item::Table(sub) = item {
                self.place_last(sub);
            }
        }
    }

    /// A new element `i` of the array of tables `section`: its comment above it, at the
    /// end of the document.
    fn added(&mut self, t: &mut toml_edit::Table, section: &str, i: usize) {
        if let Some(c) = (self.comment)(section, i) {
            let lines: String = c.lines().map(|l| format!("# {l}\n")).collect();
            t.decor_mut().set_prefix(format!("\n{lines}"));
        }
        self.place_last(t);
    }

    fn table(
        &mut self,
        t: &mut dyn toml_edit::TableLike,
        a: &toml::Table,
        b: &toml::Table,
        section: &str,
    ) -> Result<(), EditError> {
        use toml_edit::Item;
        for key in a.keys() {
            if !b.contains_key(key) {
                t.remove(key);
            }
        }
        for (key, bv) in b {
            let av = a.get(key);
            if av == Some(bv) {
                continue;
            }
            let here = if section.is_empty() {
                key.clone()
            } else {
                format!("{section}.{key}")
            };
            match (av, t.get_mut(key)) {
                (Some(av), Some(item)) => self.item(item, av, bv, &here)?,
                _ => {
                    // a key the user did not write
                    let item = match new_item(bv)? {
                        Item::ArrayOfTables(mut aot) => {
                            for (i, el) in aot.iter_mut().enumerate() {
                                self.added(el, &here, i);
                            }
                            Item::ArrayOfTables(aot)
                        }
                        Item::Table(mut sub) => {
                            self.place_last(&mut sub);
                            Item::Table(sub)
                        }
                        other => other,
                    };
                    t.insert(key, item);
                }
            }
        }
        Ok(())
    }

    fn item(
        &mut self,
        item: &mut toml_edit::Item,
        a: &toml::Value,
        b: &toml::Value,
        section: &str,
    ) -> Result<(), EditError> {
        use toml_edit::Item;
        match (a, b, &mut *item) {
            (toml::Value::Table(ta), toml::Value::Table(tb), it) if it.is_table_like() => {
                self.table(it.as_table_like_mut().expect("table-like"), ta, tb, section)
            }
            (toml::Value::Array(xa), toml::Value::Array(xb), Item::ArrayOfTables(aot))
                if xb.iter().all(toml::Value::is_table) =>
            {
                // element by element, then the new ones appended; removed ones dropped
                while aot.len() > xb.len() {
                    aot.remove(aot.len() - 1);
                }
                for (i, eb) in xb.iter().enumerate() {
                    match (xa.get(i), aot.get_mut(i)) {
                        (Some(ea), Some(t)) if ea != eb => self.table(
                            t,
                            ea.as_table().expect("a table"),
                            eb.as_table().expect("a table"),
                            section,
                        )?,
                        (Some(_), Some(_)) => {}
                        _ => {
                            let mut t = table_of(eb)?;
                            self.added(&mut t, section, i);
                            aot.push(t);
                        }
                    }
                }
                Ok(())
            }
            (_, _, Item::Value(v)) => {
                // a changed value: the key's comments kept
                let decor = v.decor().clone();
                let mut nv = edit_value(b)?;
                *nv.decor_mut() = decor;
                *v = nv;
                Ok(())
            }
            _ => {
                *item = new_item(b)?;
                Ok(())
            }
        }
    }
}

/// A value as TOML text parsed back by `toml_edit` (its spelling: `toml`'s).
fn new_item(v: &toml::Value) -> Result<toml_edit::Item, EditError> {
    let mut wrapper = toml::Table::new();
    wrapper.insert("x".into(), v.clone());
    let text = toml::to_string(&wrapper).map_err(|e| EditError(e.to_string()))?;
    let mut doc: toml_edit::DocumentMut = text
        .parse()
        .map_err(|e: toml_edit::TomlError| EditError(e.to_string()))?;
    doc.as_table_mut()
        .remove("x")
        .ok_or_else(|| EditError("a value did not survive TOML".into()))
}

fn edit_value(v: &toml::Value) -> Result<toml_edit::Value, EditError> {
    match new_item(v)? {
        toml_edit::Item::Value(v) => Ok(v),
        toml_edit::Item::Table(t) => Ok(toml_edit::Value::InlineTable(t.into_inline_table())),
        // the user wrote the array inline (`heater = [{ … }]`): it stays inline
        toml_edit::Item::ArrayOfTables(aot) => Ok(toml_edit::Value::Array(aot.into_array())),
        _ => Err(EditError("a value TOML cannot hold inline".into())),
    }
}

fn table_of(v: &toml::Value) -> Result<toml_edit::Table, EditError> {
    match new_item(&toml::Value::Array(vec![v.clone()]))? {
        toml_edit::Item::ArrayOfTables(aot) => aot
            .get(0)
            .cloned()
            .ok_or_else(|| EditError("an empty element".into())),
        toml_edit::Item::Value(toml_edit::Value::Array(a)) => match a.get(0) {
            Some(toml_edit::Value::InlineTable(t)) => Ok(t.clone().into_table()),
            _ => Err(EditError("an element that is not a table".into())),
        },
        _ => Err(EditError("an element that is not a table".into())),
    }
}
