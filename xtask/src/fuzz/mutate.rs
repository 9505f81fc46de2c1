//! The seeded mutator: byte-level mutations for any input, token-level mutations for text
//! (TOML scenes, OBJ meshes) and argument-list mutations for `sss` command lines.
//!
//! Everything is driven by [`Rng`] (SplitMix64 through `sss_util::splitmix64`), so the
//! mutants of an input are a function of the seed alone. Every mutation keeps the output at
//! most `max_len` bytes long (argument lists: at most [`MAX_ARGS`] arguments, each at most
//! `max_len` bytes).

/// A small deterministic generator: SplitMix64 over a counter.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator for `seed` and a stream (target, iteration, …), mixed so that nearby seeds
    /// and streams give unrelated sequences.
    pub fn new(seed: u64, stream: &[u64]) -> Rng {
        let mut s = sss_util::splitmix64(seed);
        for &x in stream {
            s = sss_util::splitmix64(s ^ sss_util::splitmix64_mix(x.wrapping_add(1)));
        }
        Rng(s)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(sss_util::GOLDEN_GAMMA);
        sss_util::splitmix64_mix(self.0)
    }

    /// A uniform integer in `0..n` (`n` > 0; 0 when `n` is 0).
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            return 0;
        }
        ((self.next_u64() as u128 * n as u128) >> 64) as usize
    }

    /// True with probability 1/`n`.
    pub fn one_in(&mut self, n: usize) -> bool {
        self.below(n) == 0
    }

    /// A uniformly chosen element of a non-empty slice.
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Extreme values written as text: zero, signs, the edges of f64 and of the integer types,
/// non-finite spellings and malformed numbers.
pub const EXTREME_NUMBERS: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1",
    "0.0",
    "-0.0",
    "1e308",
    "-1e308",
    "1e-308",
    "5e-324",
    "1e309",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e999999",
    "2147483647",
    "-2147483648",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551615",
    "18446744073709551616",
    "340282366920938463463374607431768211456",
    "0x7fffffff",
    "1_000_000",
    "1.",
    ".5",
    "--1",
    "1e",
];

/// Extreme binary values (little endian): integer edges and special floats.
fn interesting_binary(rng: &mut Rng) -> Vec<u8> {
    match rng.below(10) {
        0 => vec![0],
        1 => vec![0xff],
        2 => vec![0x7f],
        3 => vec![0x80],
        4 => 0u32.to_le_bytes().to_vec(),
        5 => u32::MAX.to_le_bytes().to_vec(),
        6 => (i32::MAX as u32).to_le_bytes().to_vec(),
        7 => f32::NAN.to_le_bytes().to_vec(),
        8 => f64::MAX.to_le_bytes().to_vec(),
        _ => (i32::MIN as u32).to_le_bytes().to_vec(),
    }
}

/// A long string (up to 4 KiB) of one repeated character.
fn long_string(rng: &mut Rng) -> String {
    let c = *rng.pick(&['A', '9', '[', '"', '\u{e9}', ' ', '-']);
    let n = *rng.pick(&[64usize, 255, 256, 1024, 4096]);
    std::iter::repeat_n(c, n).collect()
}

/// Text inserted by [`byte_mutation`]: an extreme number or a long string.
fn interesting_text(rng: &mut Rng) -> Vec<u8> {
    if rng.one_in(4) {
        long_string(rng).into_bytes()
    } else {
        rng.pick(EXTREME_NUMBERS).as_bytes().to_vec()
    }
}

/// A random range `start..end` of `len` bytes, at most `max` long (empty when `len` is 0).
fn range(rng: &mut Rng, len: usize, max: usize) -> (usize, usize) {
    if len == 0 {
        return (0, 0);
    }
    let start = rng.below(len);
    let n = 1 + rng.below(max.min(len - start));
    (start, start + n)
}

/// One byte-level mutation of `data`: a bit flip, a random byte, a byte range inserted,
/// deleted or duplicated, a splice with `other`, or an interesting value (binary or text)
/// overwritten or inserted. The result is truncated to `max_len` bytes.
pub fn byte_mutation(data: &[u8], other: &[u8], rng: &mut Rng, max_len: usize) -> Vec<u8> {
    let mut out = data.to_vec();
    let len = out.len();
    match rng.below(9) {
        0 if len > 0 => {
            let i = rng.below(len);
            out[i] ^= 1 << rng.below(8);
        }
        1 if len > 0 => {
            let i = rng.below(len);
            out[i] = rng.next_u64() as u8;
        }
        2 => {
            let i = rng.below(len + 1);
            let n = 1 + rng.below(16);
            let bytes: Vec<u8> = (0..n).map(|_| rng.next_u64() as u8).collect();
            out.splice(i..i, bytes);
        }
        3 if len > 0 => {
            let (a, b) = range(rng, len, 64);
            out.drain(a..b);
        }
        4 if len > 0 => {
            let (a, b) = range(rng, len, 256);
            let copy = out[a..b].to_vec();
            let at = rng.below(len + 1);
            out.splice(at..at, copy);
        }
        5 => {
            // Splice: a prefix of this input, then a suffix of the other.
            let cut = rng.below(len + 1);
            let from = rng.below(other.len() + 1);
            out.truncate(cut);
            out.extend_from_slice(&other[from..]);
        }
        6 if len > 0 => {
            let v = interesting_binary(rng);
            let i = rng.below(len);
            let end = (i + v.len()).min(len);
            out[i..end].copy_from_slice(&v[..end - i]);
        }
        7 => {
            let v = interesting_text(rng);
            let i = rng.below(len + 1);
            out.splice(i..i, v);
        }
        _ if len > 0 => {
            // Overwrite a range with an interesting text value.
            let (a, b) = range(rng, len, 8);
            out.splice(a..b, interesting_text(rng));
        }
        _ => out.push(rng.next_u64() as u8),
    }
    out.truncate(max_len);
    out
}

/// Byte ranges of the numbers in `text` (an optional sign, digits, an optional fraction and
/// exponent), not counting digits inside identifiers such as `v2` or `skin1`.
pub fn number_spans(text: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut i = 0;
    while i < text.len() {
        let starts = text[i].is_ascii_digit()
            || ((text[i] == b'-' || text[i] == b'+' || text[i] == b'.')
                && text.get(i + 1).is_some_and(u8::is_ascii_digit));
        let in_word = i > 0 && (text[i - 1].is_ascii_alphanumeric() || text[i - 1] == b'_');
        if !starts || in_word {
            i += 1;
            continue;
        }
        let start = i;
        i += 1;
        while i < text.len()
            && (text[i].is_ascii_digit()
                || text[i] == b'.'
                || text[i] == b'_'
                || ((text[i] == b'e' || text[i] == b'E') && i + 1 < text.len())
                || ((text[i] == b'-' || text[i] == b'+') && matches!(text[i - 1], b'e' | b'E')))
        {
            i += 1;
        }
        spans.push((start, i));
    }
    spans
}

/// Line ranges (without the newline) of `text`.
fn line_spans(text: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut start = 0;
    for (i, &b) in text.iter().enumerate() {
        if b == b'\n' {
            spans.push((start, i));
            start = i + 1;
        }
    }
    if start < text.len() {
        spans.push((start, text.len()));
    }
    spans
}

/// The key of a `key = value` line: the range of the key, trimmed.
fn key_span(text: &[u8], (a, b): (usize, usize)) -> Option<(usize, usize)> {
    let eq = text[a..b].iter().position(|&c| c == b'=')? + a;
    let ka = a + text[a..eq]
        .iter()
        .take_while(|c| c.is_ascii_whitespace())
        .count();
    let kb = eq
        - text[ka..eq]
            .iter()
            .rev()
            .take_while(|c| c.is_ascii_whitespace())
            .count();
    (kb > ka && !text[ka..kb].contains(&b'#')).then_some((ka, kb))
}

/// Replaces one number of `text` with one of [`EXTREME_NUMBERS`]; `None` when `text` holds no
/// number.
pub fn replace_number(text: &[u8], rng: &mut Rng) -> Option<Vec<u8>> {
    let spans = number_spans(text);
    if spans.is_empty() {
        return None;
    }
    let (a, b) = *rng.pick(&spans);
    let mut out = text.to_vec();
    out.splice(a..b, rng.pick(EXTREME_NUMBERS).bytes());
    Some(out)
}

/// One token-level mutation of a text input: a number replaced by an extreme value, a line
/// deleted or duplicated, the keys of two `key = value` lines swapped, a line spliced in from
/// `other`, or a quoted string replaced by an empty or long one. Falls back to
/// [`byte_mutation`] when the chosen mutation does not apply. At most `max_len` bytes.
pub fn token_mutation(text: &[u8], other: &[u8], rng: &mut Rng, max_len: usize) -> Vec<u8> {
    let lines = line_spans(text);
    let out: Option<Vec<u8>> = match rng.below(7) {
        0 | 1 => replace_number(text, rng),
        2 if !lines.is_empty() => {
            let (a, b) = *rng.pick(&lines);
            let mut out = text.to_vec();
            out.drain(a..(b + 1).min(text.len()));
            Some(out)
        }
        3 if !lines.is_empty() => {
            let (a, b) = *rng.pick(&lines);
            let mut line = text[a..b].to_vec();
            line.push(b'\n');
            let at = rng.pick(&lines).0;
            let mut out = text.to_vec();
            out.splice(at..at, line);
            Some(out)
        }
        4 => {
            let keys: Vec<(usize, usize)> =
                lines.iter().filter_map(|&l| key_span(text, l)).collect();
            if keys.len() < 2 {
                None
            } else {
                let (x, y) = (*rng.pick(&keys), *rng.pick(&keys));
                let (first, second) = if x.0 <= y.0 { (x, y) } else { (y, x) };
                let mut out = Vec::with_capacity(text.len());
                out.extend_from_slice(&text[..first.0]);
                out.extend_from_slice(&text[second.0..second.1]);
                out.extend_from_slice(&text[first.1..second.0.max(first.1)]);
                if second.0 >= first.1 {
                    out.extend_from_slice(&text[first.0..first.1]);
                    out.extend_from_slice(&text[second.1..]);
                } else {
                    out.extend_from_slice(&text[first.1..]);
                }
                Some(out)
            }
        }
        5 => {
            let other_lines = line_spans(other);
            if other_lines.is_empty() {
                None
            } else {
                let (a, b) = *rng.pick(&other_lines);
                let mut line = other[a..b].to_vec();
                line.push(b'\n');
                let at = lines
                    .get(rng.below(lines.len() + 1))
                    .map_or(text.len(), |l| l.0);
                let mut out = text.to_vec();
                out.splice(at..at, line);
                Some(out)
            }
        }
        _ => {
            let quotes: Vec<usize> = text
                .iter()
                .enumerate()
                .filter(|(_, c)| **c == b'"')
                .map(|(i, _)| i)
                .collect();
            if quotes.len() < 2 {
                None
            } else {
                let k = rng.below(quotes.len() / 2) * 2;
                let (a, b) = (quotes[k] + 1, quotes[k + 1]);
                let mut out = text.to_vec();
                let with = if rng.one_in(2) {
                    String::new()
                } else {
                    long_string(rng).replace('"', "'")
                };
                out.splice(a..b, with.into_bytes());
                Some(out)
            }
        }
    };
    let mut out = out.unwrap_or_else(|| byte_mutation(text, other, rng, max_len));
    out.truncate(max_len);
    out
}

/// A mutant of `data`: one to four stacked mutations, token-level ones (when `text`) three
/// times in four, byte-level otherwise. At most `max_len` bytes.
pub fn mutate(data: &[u8], other: &[u8], text: bool, rng: &mut Rng, max_len: usize) -> Vec<u8> {
    let rounds = 1 + rng.below(4);
    let mut out = data.to_vec();
    out.truncate(max_len);
    for _ in 0..rounds {
        out = if text && !rng.one_in(4) {
            token_mutation(&out, other, rng, max_len)
        } else {
            byte_mutation(&out, other, rng, max_len)
        };
    }
    out
}

/// Most arguments a mutated argument list keeps.
pub const MAX_ARGS: usize = 64;

/// A mutant of an argument list (program name first, kept): arguments replaced by or
/// inserted from `pool`, duplicated, dropped, swapped, or their values mangled (numbers made
/// extreme, strings emptied, lengthened or byte-mutated). At most [`MAX_ARGS`] arguments,
/// each at most `max_len` bytes.
pub fn mutate_args(args: &[String], pool: &[&str], rng: &mut Rng, max_len: usize) -> Vec<String> {
    let mut out: Vec<String> = args.to_vec();
    if out.is_empty() {
        out.push("sss".into());
    }
    // Mostly one change, so that most mutants still parse and run.
    let rounds = if rng.one_in(2) { 1 } else { 1 + rng.below(3) };
    for _ in 0..rounds {
        let n = out.len();
        // Index 0 is the program name.
        let pick = |rng: &mut Rng| 1 + rng.below(n.saturating_sub(1).max(1));
        // Values (not flags) are mangled more often than the list's structure is changed.
        let choice = if rng.one_in(2) { 5 } else { rng.below(7) };
        match choice {
            0 if n > 1 && !pool.is_empty() => {
                let i = pick(rng).min(n - 1);
                out[i] = rng.pick(pool).to_string();
            }
            1 if !pool.is_empty() => {
                let i = 1 + rng.below(n);
                out.insert(i.min(n), rng.pick(pool).to_string());
            }
            2 if n > 1 => {
                let i = pick(rng).min(n - 1);
                let a = out[i].clone();
                out.insert(i, a);
            }
            3 if n > 1 => {
                let i = pick(rng).min(n - 1);
                out.remove(i);
            }
            4 if n > 2 => {
                let (i, j) = (pick(rng).min(n - 1), pick(rng).min(n - 1));
                out.swap(i, j);
            }
            5 if n > 1 => {
                // A value: an argument after the subcommand that is not a flag, if any.
                let values: Vec<usize> = (2..n).filter(|&i| !out[i].starts_with("--")).collect();
                let i = if values.is_empty() {
                    pick(rng).min(n - 1)
                } else {
                    *rng.pick(&values)
                };
                let v = out[i].as_bytes();
                let m = match replace_number(v, rng) {
                    Some(m) if !rng.one_in(4) => m,
                    _ => byte_mutation(v, b"", rng, max_len),
                };
                out[i] = String::from_utf8_lossy(&m).into_owned();
            }
            _ if n > 1 => {
                let i = pick(rng).min(n - 1);
                out[i] = match rng.below(4) {
                    0 => String::new(),
                    1 => long_string(rng),
                    2 => rng.pick(EXTREME_NUMBERS).to_string(),
                    _ => format!("{},{}", out[i], rng.pick(EXTREME_NUMBERS)),
                };
            }
            _ => out.push(rng.pick(EXTREME_NUMBERS).to_string()),
        }
    }
    out.truncate(MAX_ARGS);
    for a in &mut out {
        // A process argument cannot hold NUL (and NUL separates stored arguments).
        if a.contains('\0') {
            *a = a.replace('\0', "");
        }
        if a.len() > max_len {
            let mut cut = max_len;
            while !a.is_char_boundary(cut) {
                cut -= 1;
            }
            a.truncate(cut);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOML: &[u8] = b"[camera]\nfov = 30.0\nresolution = [16, 12]\n\n[materials.skin]\ntype = \"translucent\"\npreset = \"skin1\"\nunits_per_mm = 0.05\n";

    #[test]
    fn same_seed_same_mutants_other_seed_others() {
        let run = |seed: u64| -> Vec<Vec<u8>> {
            (0..200u64)
                .map(|i| {
                    let mut rng = Rng::new(seed, &[3, i]);
                    mutate(TOML, b"v 0 0 0\n", i % 2 == 0, &mut rng, 4096)
                })
                .collect()
        };
        assert_eq!(run(7), run(7));
        assert_ne!(run(7), run(8));
        let args: Vec<String> = ["sss", "profile", "--steps", "4"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let a = mutate_args(&args, &["--log"], &mut Rng::new(5, &[1]), 256);
        let b = mutate_args(&args, &["--log"], &mut Rng::new(5, &[1]), 256);
        assert_eq!(a, b);
    }

    #[test]
    fn every_mutation_keeps_the_length_bounded() {
        let long = vec![b'7'; 3000];
        for max_len in [0usize, 1, 17, 200, 4096] {
            for i in 0..2000u64 {
                let mut rng = Rng::new(11, &[max_len as u64, i]);
                let input: &[u8] = match i % 3 {
                    0 => TOML,
                    1 => &long,
                    _ => b"",
                };
                assert!(byte_mutation(input, &long, &mut rng, max_len).len() <= max_len);
                assert!(token_mutation(input, &long, &mut rng, max_len).len() <= max_len);
                assert!(mutate(input, &long, i % 2 == 0, &mut rng, max_len).len() <= max_len);
            }
        }
        let args: Vec<String> = vec!["sss".into(), "render".into(), "x".repeat(500)];
        let pool = ["--seed", "--threads"];
        let mut a = args.clone();
        for i in 0..3000u64 {
            a = mutate_args(&a, &pool, &mut Rng::new(2, &[i]), 300);
            assert!(
                a.len() <= MAX_ARGS && a.iter().all(|s| s.len() <= 300),
                "{a:?}"
            );
        }
    }

    #[test]
    fn replacing_a_toml_number_writes_an_extreme_value() {
        for i in 0..200u64 {
            let out = replace_number(b"radius = 1.5\n", &mut Rng::new(i, &[])).unwrap();
            let out = String::from_utf8(out).unwrap();
            let value = out
                .strip_prefix("radius = ")
                .and_then(|s| s.strip_suffix('\n'))
                .unwrap_or_else(|| panic!("{out:?}"));
            assert!(EXTREME_NUMBERS.contains(&value), "{out:?}");
        }
        // Every extreme value is reachable.
        let seen: std::collections::HashSet<Vec<u8>> = (0..2000u64)
            .map(|i| replace_number(b"x = 2", &mut Rng::new(i, &[9])).unwrap())
            .collect();
        assert_eq!(seen.len(), EXTREME_NUMBERS.len());
        assert_eq!(
            replace_number(b"name = \"skin1\"", &mut Rng::new(1, &[])),
            None
        );
    }

    #[test]
    fn numbers_are_found_but_not_inside_names() {
        let text = b"v2 = [1.5, -2e-3, +7] # skin1 x .5\n";
        let found: Vec<&[u8]> = number_spans(text)
            .into_iter()
            .map(|(a, b)| &text[a..b])
            .collect();
        assert_eq!(found, vec![&b"1.5"[..], b"-2e-3", b"+7", b".5"]);
    }

    #[test]
    fn key_swaps_keep_the_values_in_place() {
        let text = b"a = 1\nbb = \"x\"\n";
        let mut swapped = false;
        for i in 0..500u64 {
            let out = token_mutation(text, b"", &mut Rng::new(i, &[4]), 1000);
            if out == b"bb = 1\na = \"x\"\n" {
                swapped = true;
            }
        }
        assert!(swapped, "no key swap among 500 mutants");
    }
}
