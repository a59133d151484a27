//! Mutation of an input: byte and word edits, brackets dropped or doubled, tokens of the input's
//! language inserted (each kind has its own vocabulary), spans repeated or deleted, numbers made
//! extreme, and spans spliced in from another file of the corpus.

use super::Kind;

const HDDL_TOKENS: &[&str] = &[
    "(",
    ")",
    "()",
    " ",
    "\n",
    "-",
    "?",
    "?x",
    ":",
    "and",
    "or",
    "not",
    "forall",
    "exists",
    "when",
    "=",
    "<",
    "+",
    "-1",
    "1.5",
    "1e9",
    "99999999999999999999",
    "evaluable",
    "either",
    ":parameters",
    ":task",
    ":subtasks",
    ":ordered-subtasks",
    ":ordering",
    ":precondition",
    ":effect",
    ":types",
    ":init",
    ":htn",
    ":objects",
    "object",
    "(< t0 t1)",
    "increase",
    "(define",
    ";",
    "\u{e9}",
    "\u{feff}",
    "\"",
    "\0",
    "123",
    ":time-travel",
    "\t",
];
const TOML_TOKENS: &[&str] = &[
    "[",
    "]",
    "[[",
    "]]",
    "{",
    "}",
    "=",
    ",",
    "\"",
    "\n",
    "1e30",
    "-1e30",
    "nan",
    "inf",
    "-0.0",
    "0",
    "1e-30",
    "999999999",
    "true",
    "[[objects]]",
    "[[agents]]",
    "name = \"x\"",
    "shape = { box = [0.1, 0.1, 0.1] }",
    "base = { x = 0, y = 0, yaw = 0 }",
    "#",
    "'",
    "\"\"\"",
    "kind = \"human\"",
    "posture = \"ready\"",
    "kind = \"robot\"",
    "urdf = \"/dev/zero\"",
    "\\u0000",
];
const PLAN_TOKENS: &[&str] = &[
    "==>",
    "<==",
    "root",
    "->",
    "0",
    "1",
    "4294967295",
    "4294967296",
    "-1",
    "\n",
    " ",
    ";",
    "x",
    "\u{e9}",
];
const JSON_TOKENS: &[&str] = &[
    "{",
    "}",
    "[",
    "]",
    ",",
    ":",
    "\"",
    "null",
    "true",
    "1e308",
    "-1e308",
    "1e999",
    "NaN",
    "0",
    "-1",
    "4294967296",
    "18446744073709551616",
    "\"frames\"",
    "\"steps\"",
    "[]",
    "{}",
    "\"format\": \"htngtp-plan\"",
    "\\u0000",
];

const XML_TOKENS: &[&str] = &[
    "<",
    ">",
    "/>",
    "</",
    "\"",
    "=",
    "<group name=\"g\">",
    "</group>",
    "<chain base_link=\"a\" tip_link=\"b\"/>",
    "<joint name=\"j\"/>",
    "<link name=\"l\"/>",
    "<group name=\"arm\"/>",
    "<end_effector name=\"e\" parent_link=\"x\" group=\"g\"/>",
    "<disable_collisions link1=\"a\" link2=\"a\" reason=\"Never\"/>",
    "<virtual_joint name=\"v\" type=\"floating\" parent_frame=\"w\" child_link=\"x\"/>",
    "<group_state name=\"s\" group=\"g\"><joint name=\"j\" value=\"1e30\"/></group_state>",
    "<triangles count=\"99999999\">",
    "<p>0 1 99999</p>",
    "<float_array count=\"3\">nan inf 1</float_array>",
    "<unit meter=\"0\"/>",
    "<matrix>0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0</matrix>",
    "<!--",
    "-->",
    "&amp;",
    "&#0;",
    "<![CDATA[",
    "solid",
    "facet normal",
    "vertex 1e30 0 0",
    "endloop",
    "v 0 0 0",
    "f 1 2 99",
    "f -1 -2 -3",
    "nan",
    "-0",
    "\n",
];

fn tokens(kind: Kind) -> &'static [&'static str] {
    match kind {
        Kind::Hddl => HDDL_TOKENS,
        Kind::Scene => TOML_TOKENS,
        Kind::PlanText => PLAN_TOKENS,
        Kind::PlanJson => JSON_TOKENS,
        Kind::Mesh | Kind::Srdf => XML_TOKENS,
    }
}

/// Whether `b` ends a word for word-level mutations.
fn delimiter(b: u8) -> bool {
    b.is_ascii_whitespace() || b"()[]{},:=\"".contains(&b)
}

/// The word of `text` around byte `i`.
fn word_at(text: &[u8], i: usize) -> (usize, usize) {
    let n = text.len();
    let mut a = i.min(n);
    while a > 0 && !delimiter(text[a - 1]) {
        a -= 1;
    }
    let mut b = a;
    while b < n && !delimiter(text[b]) {
        b += 1;
    }
    (a, b)
}

/// Applies one to four mutations to `text`; `other` is another corpus text of the same kind
/// (for splicing).
pub fn mutate(rng: &mut fastrand::Rng, kind: Kind, text: &mut Vec<u8>, other: &[u8]) {
    // Mostly one mutation: inputs near a valid file reach deeper than wrecks.
    let rounds = match rng.u8(0..10) {
        0..=6 => 1,
        7 | 8 => 2,
        _ => rng.usize(3..=6),
    };
    for _ in 0..rounds {
        mutate_once(rng, kind, text, other);
    }
    // Keep inputs bounded: a mutation that doubles spans could grow without end over rounds.
    text.truncate(4 << 20);
}

fn mutate_once(rng: &mut fastrand::Rng, kind: Kind, text: &mut Vec<u8>, other: &[u8]) {
    let n = text.len();
    let pos = |rng: &mut fastrand::Rng| rng.usize(0..=n);
    match rng.u8(0..14) {
        0 if n > 0 => {
            let a = rng.usize(0..n);
            let b = (a + rng.usize(1..=16)).min(n);
            text.drain(a..b);
        }
        1 => {
            let at = pos(rng);
            // Mostly printable ASCII; sometimes any byte (not UTF-8, control characters).
            let bytes: Vec<u8> = (0..rng.usize(1..=4))
                .map(|_| {
                    if rng.u8(0..4) == 0 {
                        rng.u8(..)
                    } else {
                        rng.u8(b' '..=b'~')
                    }
                })
                .collect();
            text.splice(at..at, bytes);
        }
        2 if n >= 2 => {
            let (a, b) = (rng.usize(0..n), rng.usize(0..n));
            text.swap(a, b);
        }
        3 | 4 => {
            // Drop or double a bracket of the language.
            let brackets: &[u8] = match kind {
                Kind::Hddl => b"()",
                Kind::Scene | Kind::PlanJson => b"[]{}\"",
                Kind::PlanText => b"\n-> ",
                Kind::Mesh | Kind::Srdf => b"<>/\"\n",
            };
            let at: Vec<usize> = (0..n).filter(|&i| brackets.contains(&text[i])).collect();
            if !at.is_empty() {
                let i = at[rng.usize(0..at.len())];
                if rng.bool() {
                    text.remove(i);
                } else {
                    let c = text[i];
                    text.insert(i, c);
                }
            }
        }
        5 | 6 => {
            let at = pos(rng);
            let toks = tokens(kind);
            let t = toks[rng.usize(0..toks.len())];
            text.splice(at..at, t.bytes().chain(std::iter::once(b' ')));
        }
        7 if n > 0 => {
            // Replace a word with another word of this text.
            let (sa, sb) = word_at(text, rng.usize(0..n));
            let (da, db) = word_at(text, rng.usize(0..n));
            let w: Vec<u8> = text[sa..sb].to_vec();
            text.splice(da..db, w);
        }
        8 if n > 0 => {
            // Duplicate a span (a declaration, an object, a step...), sometimes many times.
            let a = rng.usize(0..n);
            let b = (a + rng.usize(1..=400)).min(n);
            let chunk: Vec<u8> = text[a..b].to_vec();
            let times = if rng.u8(0..8) == 0 {
                rng.usize(2..=50)
            } else {
                1
            };
            let at = pos(rng);
            let many: Vec<u8> = chunk
                .iter()
                .copied()
                .cycle()
                .take(chunk.len() * times)
                .collect();
            text.splice(at..at, many);
        }
        9 if n > 0 => text.truncate(rng.usize(0..n)),
        10 if n > 0 => {
            // A number made extreme.
            let digits: Vec<usize> = (0..n).filter(|&i| text[i].is_ascii_digit()).collect();
            if !digits.is_empty() {
                let (a, b) = word_at(text, digits[rng.usize(0..digits.len())]);
                let extreme = [
                    "1e30",
                    "-1e30",
                    "1e308",
                    "0",
                    "-0",
                    "4294967295",
                    "99999999999999999999",
                    "1e-40",
                    "nan",
                    "inf",
                    "-1",
                    "2147483648",
                ];
                let e = extreme[rng.usize(0..extreme.len())];
                text.splice(a..b, e.bytes());
            }
        }
        11 if !other.is_empty() => {
            // Splice a span of another file in.
            let a = rng.usize(0..other.len());
            let b = (a + rng.usize(1..=400)).min(other.len());
            let at = pos(rng);
            text.splice(at..at, other[a..b].iter().copied());
        }
        12 if n > 0 => {
            // A very long word.
            let (a, b) = word_at(text, rng.usize(0..n));
            let long = vec![b'a'; rng.usize(1_000..=300_000)];
            text.splice(a..b, long);
        }
        13 if n > 0 => {
            // A line or a span deleted.
            let a = rng.usize(0..n);
            let b = text[a..]
                .iter()
                .position(|&c| c == b'\n')
                .map_or(n, |k| a + k + 1);
            text.drain(a..b);
        }
        _ => {}
    }
}
