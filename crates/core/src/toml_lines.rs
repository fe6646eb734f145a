//! Where a field of a TOML file is written: the 1-based line of a dotted field path such as
//! `robots[1].route[3]`, read from the parser's spans, so an error about a value names the line of that
//! value (not the first line that happens to contain the same word).

use std::borrow::Borrow;
use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// A TOML text parsed with spans, for looking up the line of a field.
pub struct TomlLines<'a> {
    text: &'a str,
    root: Option<Spanned<DeTable<'a>>>,
}

/// One step of a field path: a key or an array index.
enum Step<'p> {
    Key(&'p str),
    Index(usize),
}

/// Splits `robots[1].route[3]` into `robots`, 1, `route`, 3 (a bad index ends the path).
fn steps(field: &str) -> Vec<Step<'_>> {
    let mut out = Vec::new();
    for part in field.split('.') {
        let (key, rest) = part.split_once('[').map_or((part, ""), |(k, r)| (k, r));
        if !key.is_empty() {
            out.push(Step::Key(key));
        }
        for idx in rest.split('[') {
            match idx.trim_end_matches(']').parse() {
                Ok(i) => out.push(Step::Index(i)),
                Err(_) if idx.is_empty() => {}
                Err(_) => return out,
            }
        }
    }
    out
}

impl<'a> TomlLines<'a> {
    /// Parses `text`; a text that does not parse finds no field (every line is 0).
    pub fn new(text: &'a str) -> Self {
        TomlLines { text, root: DeTable::parse(text).ok() }
    }

    /// The 1-based line of byte `offset`.
    pub fn line_at(&self, offset: usize) -> usize {
        line_at(self.text, offset)
    }

    /// The line of `field` (dotted, with `[i]` indices): where its key is written, or for an array element
    /// where the element starts. When the field is absent (a default, or an error about a whole table), the
    /// line of its deepest present parent; 0 when not even the first step is present.
    pub fn line(&self, field: &str) -> usize {
        self.span(field).map_or(0, |s| self.line_at(s))
    }

    /// Byte offset where `field`, or its deepest present parent, is written.
    fn span(&self, field: &str) -> Option<usize> {
        let root = self.root.as_ref()?;
        let mut found: Option<usize> = None;
        let mut table: Option<&DeTable<'a>> = Some(root.get_ref());
        let mut value: Option<&DeValue<'a>> = None;
        for step in steps(field) {
            let next = match step {
                Step::Key(k) => {
                    let t = table.or_else(|| value.and_then(DeValue::as_table));
                    t.and_then(|t| t.iter().find(|(key, _)| Borrow::<str>::borrow(*key) == k))
                        .map(|(key, v)| (key.span().start, v))
                }
                Step::Index(i) => value.and_then(DeValue::as_array).and_then(|a| a.get(i)).map(|v| (v.span().start, v)),
            };
            let Some((at, v)) = next else { break };
            found = Some(at);
            table = None;
            value = Some(v.get_ref());
        }
        found
    }
}

/// The 1-based line of byte `offset` in `text`.
pub fn line_at(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end].iter().filter(|&&b| b == b'\n').count() + 1
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "# routes are below\nseed = 1\n\n[merge]\nhost = \"a\"\n\n[[robots]]\nname = \"a\"\nspeed = 0.4\n\
        route = [[1, 2],\n  [3, 4]]\n\n[[robots]]\nname = \"b\"\nspeed = -0.4\nslip = { rate = 2 }\n";

    #[test]
    fn fields_are_found_where_they_are_written() {
        let t = TomlLines::new(TEXT);
        assert_eq!(t.line("seed"), 2);
        assert_eq!(t.line("merge.host"), 5);
        assert_eq!(t.line("robots[0].speed"), 9);
        assert_eq!(t.line("robots[1].speed"), 15);
        assert_eq!(t.line("robots[1].name"), 14);
        assert_eq!(t.line("robots[0].route[1]"), 11);
        assert_eq!(t.line("robots[1].slip.rate"), 16);
    }

    #[test]
    fn an_absent_field_points_at_its_parent() {
        let t = TomlLines::new(TEXT);
        assert_eq!(t.line("robots[1].lookahead"), t.line("robots[1]"));
        assert!((13..=14).contains(&t.line("robots[1]")), "{}", t.line("robots[1]"));
        assert_eq!(t.line("merge.ratio"), 4);
        assert_eq!(t.line("nothing"), 0);
        assert_eq!(TomlLines::new("not = = toml").line("not"), 0);
    }
}
