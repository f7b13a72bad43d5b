//! Where things stand in a scene file's text: the start of each item of a
//! top-level list (`walls`, `lights`, `glass`) and of a top-level field's
//! value, for validation errors that the RON parser cannot place itself
//! (those that need more than one value, such as a spot's cone against its
//! softness).
//!
//! A small scanner of RON's lexical structure: it skips strings, raw
//! strings, characters and comments (nested block comments too), and
//! counts brackets, so that text inside a comment or a string is never
//! taken for an item.

/// The byte offset where each item of the top-level list `field` starts,
/// in order. Empty when the field is absent or not a list.
pub(crate) fn list_items(text: &str, field: &str) -> Vec<usize> {
    let Some(start) = field_value(text, field) else {
        return Vec::new();
    };
    let bytes = text.as_bytes();
    if bytes.get(start) != Some(&b'[') {
        return Vec::new();
    }
    let mut items = Vec::new();
    let mut depth = 0usize;
    let mut expecting = true;
    for token in Tokens::new(text, start) {
        match token.kind {
            Kind::Open => {
                depth += 1;
                if depth == 1 {
                    expecting = true;
                    continue;
                }
            }
            Kind::Close => {
                if depth == 1 {
                    break;
                }
                depth = depth.saturating_sub(1);
                continue;
            }
            Kind::Comma if depth == 1 => {
                expecting = true;
                continue;
            }
            _ => {}
        }
        if depth >= 1 && expecting {
            items.push(token.at);
            expecting = false;
        }
    }
    items
}

/// The byte offset where the value of the top-level field `field` starts
/// (after its colon), if the field is there.
pub(crate) fn field_value(text: &str, field: &str) -> Option<usize> {
    let mut depth = 0usize;
    let mut tokens = Tokens::new(text, 0);
    while let Some(token) = tokens.next() {
        match token.kind {
            Kind::Open => depth += 1,
            Kind::Close => depth = depth.saturating_sub(1),
            Kind::Word if depth == 1 && &text[token.at..token.end] == field => {
                let colon = tokens.next()?;
                if colon.kind == Kind::Colon {
                    return tokens.next().map(|value| value.at);
                }
            }
            _ => {}
        }
    }
    None
}

/// The 1-based line and column (in characters) of byte `offset`.
pub(crate) fn position(text: &str, offset: usize) -> (usize, usize) {
    let offset = floor_char_boundary(text, offset.min(text.len()));
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

/// The byte range of the value that starts at `start` (a number, a word,
/// a string, or a bracketed value with what follows its name), up to the
/// comma or closing bracket after it.
pub(crate) fn value_end(text: &str, start: usize) -> usize {
    let mut depth = 0usize;
    let mut end = start;
    for token in Tokens::new(text, start) {
        match token.kind {
            Kind::Open => depth += 1,
            Kind::Close if depth == 0 => return end,
            Kind::Close => {
                depth -= 1;
                if depth == 0 {
                    end = token.end;
                    continue;
                }
            }
            Kind::Comma if depth == 0 => return end,
            _ => {}
        }
        end = token.end;
    }
    end
}

/// The byte range of item `k` of the top-level list `list`.
pub(crate) fn item_range(text: &str, list: &str, k: usize) -> Option<(usize, usize)> {
    let start = *list_items(text, list).get(k)?;
    Some((start, value_end(text, start)))
}

/// The byte range of the value of field `field` directly inside the item
/// that spans `item` (a `Name(field: value, ...)`), if the item has it.
pub(crate) fn item_field(text: &str, item: (usize, usize), field: &str) -> Option<(usize, usize)> {
    let mut depth = 0usize;
    let mut tokens = Tokens::new(text, item.0).peekable();
    while let Some(token) = tokens.next() {
        if token.at >= item.1 {
            break;
        }
        match token.kind {
            Kind::Open => depth += 1,
            Kind::Close => depth = depth.saturating_sub(1),
            Kind::Word
                if depth == 1
                    && &text[token.at..token.end] == field
                    && tokens.peek().is_some_and(|t| t.kind == Kind::Colon) =>
            {
                tokens.next();
                let value = tokens.next()?;
                return Some((value.at, value_end(text, value.at)));
            }
            _ => {}
        }
    }
    None
}

/// The byte offset of 1-based `line` and `column` (in characters), as
/// the RON parser reports them; the end of the text past its last line.
pub(crate) fn offset(text: &str, line: usize, column: usize) -> usize {
    let mut at = 0;
    for (k, l) in text.split_inclusive('\n').enumerate() {
        if k + 1 == line {
            let within = l
                .char_indices()
                .nth(column.saturating_sub(1))
                .map_or(l.len(), |(i, _)| i);
            return at + within;
        }
        at += l.len();
    }
    text.len()
}

/// What surrounds byte `offset` of a scene's text, for messages that say
/// what was meant: the token before it, the field whose value it is in,
/// and the constructor it stands in.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Context {
    /// The last token that ends at or before `offset`: its start, its
    /// end, and its text.
    pub previous: Option<(usize, usize, String)>,
    /// The nearest field name (`name:`) whose value holds `offset`.
    pub field: Option<String>,
    /// The name before the innermost `(` that holds `offset`
    /// (`Reinhard` in `Reinhard(4)`), if it has one.
    pub enclosing: Option<String>,
}

/// The [`Context`] of byte `offset`.
pub(crate) fn context(text: &str, offset: usize) -> Context {
    // One frame per open bracket: the name before it, and the field whose
    // value is being read inside it.
    let mut frames: Vec<(Option<String>, Option<String>)> = vec![(None, None)];
    let mut previous: Option<Token> = None;
    let mut tokens = Tokens::new(text, 0).peekable();
    while let Some(token) = tokens.next() {
        if token.at >= offset {
            break;
        }
        let word = |t: &Token| text[t.at..t.end].to_string();
        match token.kind {
            Kind::Open => {
                let name = previous
                    .filter(|p| p.kind == Kind::Word && p.end == token.at)
                    .map(|p| word(&p));
                frames.push((name, None));
            }
            Kind::Close if frames.len() > 1 => {
                frames.pop();
            }
            Kind::Word if tokens.peek().is_some_and(|t| t.kind == Kind::Colon) => {
                if let Some(top) = frames.last_mut() {
                    top.1 = Some(word(&token));
                }
            }
            _ => {}
        }
        if token.end <= offset {
            previous = Some(token);
        }
    }
    Context {
        previous: previous.map(|t| (t.at, t.end, text[t.at..t.end].to_string())),
        field: frames.iter().rev().find_map(|f| f.1.clone()),
        enclosing: frames.last().and_then(|f| f.0.clone()),
    }
}

fn floor_char_boundary(text: &str, mut offset: usize) -> usize {
    while offset > 0 && !text.is_char_boundary(offset) {
        offset -= 1;
    }
    offset
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// `(`, `[` or `{`.
    Open,
    /// `)`, `]` or `}`.
    Close,
    Comma,
    Colon,
    /// An identifier or a number.
    Word,
    /// A string, raw string or character literal.
    Literal,
    /// Anything else (a sign, a stray symbol).
    Other,
}

#[derive(Clone, Copy, Debug)]
struct Token {
    kind: Kind,
    at: usize,
    end: usize,
}

/// RON tokens from a byte offset on, comments and white space skipped.
struct Tokens<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str, at: usize) -> Tokens<'a> {
        Tokens {
            bytes: text.as_bytes(),
            at,
        }
    }

    fn peek(&self, k: usize) -> Option<u8> {
        self.bytes.get(self.at + k).copied()
    }

    /// Skips white space and comments.
    fn skip_blank(&mut self) {
        loop {
            match (self.peek(0), self.peek(1)) {
                (Some(c), _) if c.is_ascii_whitespace() => self.at += 1,
                (Some(b'/'), Some(b'/')) => {
                    while let Some(c) = self.peek(0) {
                        self.at += 1;
                        if c == b'\n' {
                            break;
                        }
                    }
                }
                (Some(b'/'), Some(b'*')) => {
                    self.at += 2;
                    let mut depth = 1;
                    while depth > 0 && self.at < self.bytes.len() {
                        match (self.peek(0), self.peek(1)) {
                            (Some(b'/'), Some(b'*')) => {
                                depth += 1;
                                self.at += 2;
                            }
                            (Some(b'*'), Some(b'/')) => {
                                depth -= 1;
                                self.at += 2;
                            }
                            _ => self.at += 1,
                        }
                    }
                }
                _ => return,
            }
        }
    }

    /// Skips a quoted literal that opens at the current byte with `quote`.
    fn skip_quoted(&mut self, quote: u8) {
        self.at += 1;
        while let Some(c) = self.peek(0) {
            self.at += 1;
            if c == b'\\' {
                self.at += 1;
            } else if c == quote {
                return;
            }
        }
    }

    /// Skips a raw string `r#"..."#` whose `r` is the current byte, if it
    /// is one; returns whether it was.
    fn skip_raw(&mut self) -> bool {
        let mut hashes = 0;
        while self.peek(1 + hashes) == Some(b'#') {
            hashes += 1;
        }
        if self.peek(1 + hashes) != Some(b'"') {
            return false;
        }
        self.at += 2 + hashes;
        while self.at < self.bytes.len() {
            if self.peek(0) == Some(b'"') && (1..=hashes).all(|k| self.peek(k) == Some(b'#')) {
                self.at += 1 + hashes;
                return true;
            }
            self.at += 1;
        }
        true
    }
}

impl Iterator for Tokens<'_> {
    type Item = Token;

    fn next(&mut self) -> Option<Token> {
        self.skip_blank();
        let at = self.at;
        let c = self.peek(0)?;
        let kind = match c {
            b'(' | b'[' | b'{' => {
                self.at += 1;
                Kind::Open
            }
            b')' | b']' | b'}' => {
                self.at += 1;
                Kind::Close
            }
            b',' => {
                self.at += 1;
                Kind::Comma
            }
            b':' => {
                self.at += 1;
                Kind::Colon
            }
            b'"' => {
                self.skip_quoted(b'"');
                Kind::Literal
            }
            b'\'' => {
                self.skip_quoted(b'\'');
                Kind::Literal
            }
            b'r' if self.skip_raw() => Kind::Literal,
            c if c.is_ascii_alphanumeric() || c == b'_' || c == b'.' || c >= 0x80 => {
                while let Some(c) = self.peek(0) {
                    if c.is_ascii_alphanumeric() || c == b'_' || c == b'.' || c >= 0x80 {
                        self.at += 1;
                    } else {
                        break;
                    }
                }
                Kind::Word
            }
            _ => {
                self.at += 1;
                Kind::Other
            }
        };
        Some(Token {
            kind,
            at,
            end: self.at,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_are_found_past_comments_strings_and_nesting() {
        let text = "Scene(\n  // lights: [Line(a: (0, 0))]\n  floor: Image(\"lights: [x]\"),\n  lights: [\n    /* Spot( */ Point(at: (1, 2)),\n    Spot(at: (3, 4), direction: (1, 0)),\n\n    Line(a: (0, 0), b: (1, 1)),\n  ],\n)";
        let items = list_items(text, "lights");
        let at: Vec<(usize, usize)> = items.iter().map(|&o| position(text, o)).collect();
        assert_eq!(at, vec![(5, 17), (6, 5), (8, 5)]);
        assert_eq!(
            position(text, field_value(text, "floor").unwrap_or(0)),
            (3, 10)
        );
        assert!(list_items(text, "walls").is_empty());
        // A trailing comma adds no item.
        assert_eq!(list_items("(walls: [A, B,])", "walls").len(), 2);
    }

    #[test]
    fn items_and_their_fields_have_ranges() {
        let text = "Scene(lights: [\n  Point(at: (1, 2), color: (1, 1, 1)), // a lamp\n  Spot(at: (3, 4), cone: 30),\n])";
        let (start, end) = item_range(text, "lights", 1).unwrap();
        assert_eq!(&text[start..end], "Spot(at: (3, 4), cone: 30)");
        let (a, b) = item_field(text, item_range(text, "lights", 0).unwrap(), "color").unwrap();
        assert_eq!(&text[a..b], "(1, 1, 1)");
        let (a, b) = item_field(text, (start, end), "cone").unwrap();
        assert_eq!(&text[a..b], "30");
        assert_eq!(item_field(text, (start, end), "color"), None);
        assert_eq!(item_range(text, "lights", 2), None);
    }

    #[test]
    fn context_names_the_field_the_constructor_and_the_token_before() {
        let text =
            "Scene(\n  canvas: (360.5, 240), // a comment\n  render: (tonemap: Reinhard(4)),\n)";
        let at = text.find(".5").unwrap();
        let c = context(text, at);
        assert_eq!(c.field.as_deref(), Some("canvas"));
        assert_eq!(c.enclosing, None);
        // `360.5` holds the offset: the token before it is the bracket.
        assert_eq!(c.previous.map(|p| p.2), Some("(".to_string()));
        let c = context(text, text.find("4)").unwrap());
        assert_eq!(c.field.as_deref(), Some("tonemap"));
        assert_eq!(c.enclosing.as_deref(), Some("Reinhard"));
        // The comment is skipped: the token before `render` is the comma.
        let c = context(text, text.find("render").unwrap());
        assert_eq!(c.previous.map(|p| p.2), Some(",".to_string()));
        let (line, column) = position(text, at);
        assert_eq!(offset(text, line, column), at);
    }
}
