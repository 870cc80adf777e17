//! PIZ's Huffman coding (`ImfHuf`), decoding only: a canonical code of up
//! to 58 bits per symbol, its lengths stored packed in 6 bits with runs of
//! zeros, one symbol reserved for runs of the value before, and a 14-bit
//! lookup table; a longer code (float samples make most codes long) is
//! found among the canonical code's ranges by length, from the shortest to
//! the longest of those that share its first 14 bits. Small tables that
//! stay in the first cache beat a second level of tables here: decoding
//! waits on memory, not on the few comparisons.

const ENCODE_SIZE: usize = (1 << 16) + 1;
const DECODE_BITS: u32 = 14;
const DECODE_SIZE: usize = 1 << DECODE_BITS;
const SHORT_ZEROCODE_RUN: u64 = 59;
const LONG_ZEROCODE_RUN: u64 = 63;
const SHORTEST_LONG_RUN: u64 = 2 + LONG_ZEROCODE_RUN - SHORT_ZEROCODE_RUN;

/// An entry of the lookup table: a short code's length (high byte) and
/// symbol, or [`LONG`] and the shortest (bits 8–15) and longest (low
/// byte) lengths of the long codes that start with its bits, or 0 for
/// none.
type Entry = u32;

/// The mark of an entry for long codes.
const LONG: u32 = 0xff00_0000;

/// The lookup table of the 14-bit prefixes, and the whole code by length
/// for the long codes.
struct Table {
    entries: Vec<Entry>,
    canonical: Canonical,
}

/// The canonical code by length (longer codes are numerically lower):
/// the codes of length `l`, left-aligned in 64 bits, start at `base[l]`,
/// and their symbols, in code order, at `symbols[first[l]..]`.
struct Canonical {
    base: [u64; 59],
    first: [u32; 59],
    count: [u32; 59],
    symbols: Vec<u32>,
}

impl Canonical {
    fn new(codes: &[u64], min: usize, max: usize) -> Canonical {
        let mut count = [0u32; 59];
        let mut base = [u64::MAX; 59];
        for &entry in &codes[min..=max] {
            let length = (entry & 63) as usize;
            if length > 0 {
                count[length] += 1;
                base[length] = base[length].min((entry >> 6) << (64 - length));
            }
        }
        let mut first = [0u32; 59];
        let mut total = 0;
        for (first, count) in first.iter_mut().zip(count) {
            *first = total;
            total += count;
        }
        let mut symbols = vec![0; total as usize];
        let mut next = first;
        // Codes of one length rise with the symbol (`hufCanonicalCodeTable`).
        for (symbol, &entry) in codes.iter().enumerate().take(max + 1).skip(min) {
            let length = (entry & 63) as usize;
            if length > 0 {
                symbols[next[length] as usize] = symbol as u32;
                next[length] += 1;
            }
        }
        Canonical {
            base,
            first,
            count,
            symbols,
        }
    }

    /// The symbol and length of the code at the front of `bits` (left-aligned,
    /// valid for `longest` bits), among the lengths `shortest..=longest`.
    #[inline]
    fn find(&self, bits: u64, shortest: u32, longest: u32) -> Option<(u32, u32)> {
        for length in shortest..=longest {
            let l = length as usize;
            if self.count[l] > 0 && bits >= self.base[l] {
                let index = (bits - self.base[l]) >> (64 - length);
                return (index < u64::from(self.count[l])).then(|| {
                    (
                        self.symbols[(self.first[l] as u64 + index) as usize],
                        length,
                    )
                });
            }
        }
        None
    }
}

/// Bits read from the front of a byte slice, most significant first, by
/// position.
struct Bits<'a> {
    bytes: &'a [u8],
    /// Bits used so far.
    at: usize,
}

impl Bits<'_> {
    /// The next 57 bits or more, left-aligned (zeros past the end).
    #[inline(always)]
    fn peek(&self) -> u64 {
        let byte = self.at >> 3;
        let word = match self.bytes.get(byte..byte + 8) {
            Some(b) => u64::from_be_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
            None => self.peek_end(byte),
        };
        word << (self.at & 7)
    }

    /// The last bytes, padded with zeros.
    #[cold]
    fn peek_end(&self, byte: usize) -> u64 {
        let mut b = [0u8; 8];
        let tail = self.bytes.get(byte..).unwrap_or(&[]);
        b[..tail.len().min(8)].copy_from_slice(&tail[..tail.len().min(8)]);
        u64::from_be_bytes(b)
    }

    /// The next `n` (at most 64) bits, for long codes.
    fn peek_long(&self, n: u32) -> u64 {
        let byte = self.at >> 3;
        let mut b = [0u8; 16];
        let tail = self.bytes.get(byte..).unwrap_or(&[]);
        let n_bytes = tail.len().min(16);
        b[..n_bytes].copy_from_slice(&tail[..n_bytes]);
        let word = u128::from_be_bytes(b) << (self.at & 7);
        (word >> (128 - n)) as u64
    }

    fn take(&mut self, n: u32) -> Result<u64, String> {
        if self.at + n as usize > self.bytes.len() * 8 {
            return Err(short());
        }
        let value = self.peek() >> (64 - n);
        self.at += n as usize;
        Ok(value)
    }
}

/// The coded bits, most significant first, through a 64-bit buffer.
struct Reader<'a> {
    bytes: &'a [u8],
    /// The next byte to load.
    next: usize,
    /// Bits loaded and not used, left-aligned.
    buffer: u64,
    count: u32,
    /// Bits used so far.
    used: usize,
}

impl<'a> Reader<'a> {
    fn new(bytes: &'a [u8]) -> Reader<'a> {
        Reader {
            bytes,
            next: 0,
            buffer: 0,
            count: 0,
            used: 0,
        }
    }

    /// At least 32 bits in the buffer (zeros past the end).
    #[inline(always)]
    fn refill(&mut self) {
        if self.count >= 32 {
            return;
        }
        let word = match self.bytes.get(self.next..self.next + 4) {
            Some(b) => u32::from_be_bytes([b[0], b[1], b[2], b[3]]),
            None => {
                let mut b = [0u8; 4];
                let tail = self.bytes.get(self.next..).unwrap_or(&[]);
                b[..tail.len().min(4)].copy_from_slice(&tail[..tail.len().min(4)]);
                u32::from_be_bytes(b)
            }
        };
        self.buffer |= u64::from(word) << (32 - self.count);
        self.count += 32;
        self.next += 4;
    }

    #[inline(always)]
    fn consume(&mut self, n: u32) {
        if n <= self.count {
            self.buffer <<= n;
            self.count -= n;
            self.used += n as usize;
        } else {
            // A long code: reload the buffer past it.
            self.used += n as usize;
            self.next = self.used / 8;
            self.buffer = 0;
            self.count = 0;
            self.refill();
            let skip = (self.used % 8) as u32;
            self.buffer <<= skip;
            self.count -= skip;
        }
    }

    /// The next `n` (at most 64) bits, for long codes.
    #[inline]
    fn peek_long(&self, n: u32) -> u64 {
        if n <= self.count {
            return self.buffer >> (64 - n);
        }
        Bits {
            bytes: self.bytes,
            at: self.used,
        }
        .peek_long(n)
    }
}

fn short() -> String {
    "a PIZ chunk's Huffman data ends early".to_string()
}

fn damaged() -> String {
    "a PIZ chunk's Huffman data is damaged".to_string()
}

fn read_u32(bytes: &[u8], at: usize) -> Result<usize, String> {
    let b: [u8; 4] = bytes
        .get(at..at + 4)
        .and_then(|b| b.try_into().ok())
        .ok_or_else(short)?;
    Ok(u32::from_le_bytes(b) as usize)
}

/// The code lengths of symbols `min..=max` (`hufUnpackEncTable`), then
/// each symbol's canonical code: length in the low 6 bits, code above.
fn code_table(bits: &mut Bits, min: usize, max: usize) -> Result<Vec<u64>, String> {
    let mut codes = vec![0u64; ENCODE_SIZE];
    let mut symbol = min;
    while symbol <= max {
        let length = bits.take(6)?;
        let zeros = if length == LONG_ZEROCODE_RUN {
            bits.take(8)? + SHORTEST_LONG_RUN
        } else if length >= SHORT_ZEROCODE_RUN {
            length - SHORT_ZEROCODE_RUN + 2
        } else {
            codes[symbol] = length;
            symbol += 1;
            continue;
        };
        let zeros = zeros as usize;
        if symbol + zeros > max + 1 {
            return Err(damaged());
        }
        symbol += zeros;
    }
    // The numerically lowest code of each length, from the longest
    // (`hufCanonicalCodeTable`).
    let mut count = [0u64; 59];
    for &length in &codes {
        count[length as usize] += 1;
    }
    let mut code = 0u64;
    for length in (1..=58).rev() {
        let next = (code + count[length]) >> 1;
        count[length] = code;
        code = next;
    }
    for entry in &mut codes {
        let length = *entry as usize;
        if length > 0 {
            *entry = length as u64 | (count[length] << 6);
            count[length] += 1;
        }
    }
    Ok(codes)
}

/// The lookup table of `codes` for symbols `min..=max`
/// (`hufBuildDecTable`).
fn lookup(codes: &[u64], min: usize, max: usize) -> Result<Table, String> {
    let mut entries = vec![0; DECODE_SIZE];
    for (symbol, &entry) in codes.iter().enumerate().take(max + 1).skip(min) {
        let code = entry >> 6;
        let length = (entry & 63) as u32;
        if length == 0 {
            continue;
        }
        if code >> length != 0 {
            return Err(damaged());
        }
        if length > DECODE_BITS {
            let slot = &mut entries[(code >> (length - DECODE_BITS)) as usize];
            if *slot == 0 {
                *slot = LONG | (length << 8) | length;
            } else if *slot & LONG != LONG {
                return Err(damaged());
            }
            let (shortest, longest) = ((*slot >> 8) & 0xff, *slot & 0xff);
            *slot = LONG | (shortest.min(length) << 8) | longest.max(length);
        } else {
            let first = (code << (DECODE_BITS - length)) as usize;
            for slot in &mut entries[first..first + (1 << (DECODE_BITS - length))] {
                if *slot != 0 {
                    return Err(damaged());
                }
                *slot = (length << 24) | symbol as u32;
            }
        }
    }
    Ok(Table {
        entries,
        canonical: Canonical::new(codes, min, max),
    })
}

/// `count` values from a Huffman-coded chunk (`hufUncompress`).
pub(super) fn decompress(data: &[u8], count: usize) -> Result<Vec<u16>, String> {
    if data.is_empty() {
        return if count == 0 {
            Ok(Vec::new())
        } else {
            Err(short())
        };
    }
    let (min, max) = (read_u32(data, 0)?, read_u32(data, 4)?);
    let bit_count = read_u32(data, 12)?;
    if min >= ENCODE_SIZE || max >= ENCODE_SIZE || min > max {
        return Err(damaged());
    }
    let mut table_bits = Bits {
        bytes: data.get(20..).ok_or_else(short)?,
        at: 0,
    };
    let codes = code_table(&mut table_bits, min, max)?;
    let coded = &data[20 + table_bits.at.div_ceil(8)..];
    if bit_count.div_ceil(8) > coded.len() {
        return Err(short());
    }
    let table = lookup(&codes, min, max)?;
    // The run symbol: the value before, as many more times as the next
    // 8 bits say.
    let run = max as u32;
    let mut out = vec![0u16; count];
    let mut n: usize = 0;
    let mut bits = Reader::new(&coded[..bit_count.div_ceil(8)]);
    while bits.used < bit_count {
        bits.refill();
        let entry = table.entries[(bits.buffer >> (64 - DECODE_BITS)) as usize];
        let (symbol, length) = if entry & LONG == LONG {
            let (shortest, longest) = ((entry >> 8) & 0xff, entry & 0xff);
            let front = bits.peek_long(longest) << (64 - longest);
            table
                .canonical
                .find(front, shortest, longest)
                .ok_or_else(damaged)?
        } else if entry == 0 {
            return Err(damaged());
        } else {
            (entry & 0xff_ffff, entry >> 24)
        };
        bits.consume(length);
        if symbol == run {
            bits.refill();
            let repeat = (bits.buffer >> 56) as usize;
            bits.consume(8);
            let last = *n
                .checked_sub(1)
                .and_then(|i: usize| out.get(i))
                .ok_or_else(damaged)?;
            let end = n + repeat;
            out.get_mut(n..end).ok_or_else(damaged)?.fill(last);
            n = end;
        } else {
            *out.get_mut(n).ok_or_else(damaged)? = symbol as u16;
            n += 1;
        }
        if bits.used > bit_count {
            return Err(damaged());
        }
    }
    if n != count {
        return Err(short());
    }
    Ok(out)
}
