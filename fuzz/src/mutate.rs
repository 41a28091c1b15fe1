//! Byte-level mutations with a dictionary of each language's tokens: text readers are
//! reached far sooner by splicing whole words, numbers and brackets than by flipping bits.

use crate::guard::MAX_INPUT;

/// xorshift64*: small, fast and reproducible from a seed.
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed (any value).
    pub fn new(seed: u64) -> Rng {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    /// The next 64 random bits.
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in `0..n` (`n` > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// Numbers that break arithmetic: zero, signs, extremes, non-finite spellings.
const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "0.5",
    "1e308",
    "-1e308",
    "1e309",
    "1e-320",
    "4294967296",
    "18446744073709551616",
    "9223372036854775807",
    "-9223372036854775808",
    "65536",
    "1000000",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e",
    ".",
    "0x10",
    "1_000",
    "3.14159",
];

/// Mutants grow to at most this many bytes (libFuzzer's default `-max_len`), or the
/// parent's length if longer: hit-count novelty otherwise rewards ever longer
/// repetitions, and a corpus of 50 kB inputs ran ten times slower for no new edges.
pub const MAX_GROWTH: usize = 4096;

/// Mutates `data` in place with 1 to 8 stacked edits; `dict` holds the language's tokens,
/// `other` an input of the corpus to splice from.
pub fn mutate(data: &mut Vec<u8>, rng: &mut Rng, dict: &[Vec<u8>], other: &[u8]) {
    let cap = data.len().clamp(MAX_GROWTH, MAX_INPUT);
    let n = 1 << rng.below(4);
    for _ in 0..n {
        edit(data, rng, dict, other);
    }
    data.truncate(cap);
}

fn edit(d: &mut Vec<u8>, rng: &mut Rng, dict: &[Vec<u8>], other: &[u8]) {
    let len = d.len();
    let at = |rng: &mut Rng| rng.below(len + 1);
    match rng.below(14) {
        0 if len > 0 => {
            let i = rng.below(len);
            d[i] ^= 1 << rng.below(8);
        }
        1 if len > 0 => {
            let i = rng.below(len);
            d[i] = rng.next() as u8;
        }
        2 if len > 0 => {
            // Delete a run.
            let i = rng.below(len);
            let k = 1 + rng.below((len - i).min(32));
            d.drain(i..i + k);
        }
        3 => {
            let i = at(rng);
            let b = [
                b'(', b')', b'[', b']', b'{', b'}', b'"', b',', b';', b'=', b'\n', b' ',
            ][rng.below(12)];
            d.insert(i, b);
        }
        4..=6 if !dict.is_empty() => {
            // Insert or overwrite with a token.
            let t = &dict[rng.below(dict.len())];
            let i = at(rng);
            if rng.below(2) == 0 || i + t.len() > len {
                d.splice(i..i, t.iter().copied());
            } else {
                d.splice(i..i + t.len(), t.iter().copied());
            }
        }
        7 => replace_number(d, rng),
        8 if len > 1 => {
            // Duplicate a run (repetition finds limits and quadratic paths).
            let i = rng.below(len);
            let k = 1 + rng.below((len - i).min(256));
            let run: Vec<u8> = d[i..i + k].to_vec();
            let most = if rng.below(8) == 0 { 64 } else { 4 };
            let times = 1 + rng.below(most);
            let j = at(rng);
            for _ in 0..times {
                d.splice(j..j, run.iter().copied());
            }
        }
        9 if !other.is_empty() => {
            // Splice: our head with the other input's tail, or a chunk of it inserted.
            let j = rng.below(other.len());
            if rng.below(2) == 0 {
                d.truncate(at(rng));
                d.extend_from_slice(&other[j..]);
            } else {
                let k = 1 + rng.below((other.len() - j).min(512));
                let i = at(rng);
                d.splice(i..i, other[j..j + k].iter().copied());
            }
        }
        10 if len > 1 => {
            // Swap two lines' worth of text: reorders statements and keys.
            let i = rng.below(len);
            let j = rng.below(len);
            let (a, b) = (i.min(j), i.max(j));
            let k = (b - a).min(len - b).min(1 + rng.below(64));
            for o in 0..k {
                d.swap(a + o, b + o);
            }
        }
        11 => {
            // Nesting: many open brackets (depth limits).
            let i = at(rng);
            let open = [&b"("[..], b"[", b"{", b"-", b"!", b"sin("][rng.below(6)];
            let times = 1 + rng.below(300);
            for _ in 0..times {
                d.splice(i..i, open.iter().copied());
            }
        }
        12 if len > 0 => {
            // Truncate.
            d.truncate(rng.below(len));
        }
        _ => {
            let i = at(rng);
            let num = NUMBERS[rng.below(NUMBERS.len())].as_bytes();
            d.splice(i..i, num.iter().copied());
        }
    }
}

/// Replaces one number in the text with an awkward one.
fn replace_number(d: &mut Vec<u8>, rng: &mut Rng) {
    let starts: Vec<usize> = (0..d.len())
        .filter(|&i| d[i].is_ascii_digit() && (i == 0 || !d[i - 1].is_ascii_alphanumeric()))
        .collect();
    if starts.is_empty() {
        return;
    }
    let i = starts[rng.below(starts.len())];
    let mut j = i;
    while j < d.len() && (d[j].is_ascii_digit() || matches!(d[j], b'.' | b'e' | b'E')) {
        j += 1;
    }
    let num = NUMBERS[rng.below(NUMBERS.len())].as_bytes();
    d.splice(i..j, num.iter().copied());
}

/// The tokens of some texts: identifiers, numbers and runs of punctuation, each once.
pub fn tokens<'a>(texts: impl IntoIterator<Item = &'a [u8]>) -> Vec<Vec<u8>> {
    let mut set = std::collections::BTreeSet::new();
    for t in texts {
        let mut i = 0;
        while i < t.len() {
            let c = t[i];
            let class = |b: u8| {
                if b.is_ascii_alphanumeric() || b == b'_' || b == b'-' && c.is_ascii_alphabetic() {
                    0
                } else if b.is_ascii_whitespace() {
                    1
                } else {
                    2
                }
            };
            let k = class(c);
            let mut j = i + 1;
            while j < t.len() && class(t[j]) == k && (k != 2 || j - i < 3) {
                j += 1;
            }
            if k != 1 && j - i <= 32 {
                set.insert(t[i..j].to_vec());
            }
            i = j;
        }
    }
    set.into_iter().collect()
}
