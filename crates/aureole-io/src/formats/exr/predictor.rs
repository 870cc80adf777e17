//! The byte predictor that OpenEXR's ZIP and RLE compressions share
//! (`ImfZip`, `ImfRle`): a block's bytes split into the even ones, then
//! the odd ones, each stored as its difference to the one before, plus
//! 128. Float samples' bytes then change slowly and compress well.

/// The even bytes, then the odd ones, as differences.
#[cfg(test)]
pub(crate) fn predict(raw: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    predict_into(raw, &mut Vec::new(), &mut out);
    out
}

/// [`predict`] into `out`, through `split`: buffers a thread keeps.
pub(crate) fn predict_into(raw: &[u8], split: &mut Vec<u8>, out: &mut Vec<u8>) {
    let half = raw.len().div_ceil(2);
    // Resized, not cleared: chunks of one size write no zeros.
    split.resize(raw.len(), 0);
    out.resize(raw.len(), 0);
    let (even, odd) = split.split_at_mut(half);
    for ((pair, e), o) in raw.chunks_exact(2).zip(even.iter_mut()).zip(odd.iter_mut()) {
        *e = pair[0];
        *o = pair[1];
    }
    if raw.len() % 2 == 1 {
        even[half - 1] = raw[raw.len() - 1];
    }
    if let (Some((first, rest)), Some(&value)) = (out.split_first_mut(), split.first()) {
        *first = value;
        for (o, pair) in rest.iter_mut().zip(split.windows(2)) {
            *o = pair[1].wrapping_sub(pair[0]).wrapping_add(128);
        }
    }
}

/// [`predict`] undone, in place of `predicted`'s bytes.
pub(crate) fn unpredict(predicted: &mut [u8]) -> Vec<u8> {
    // A running sum of the differences. Within blocks of 8 the sums do not
    // wait on the block before, which leaves one addition per block on
    // the chain from byte to byte instead of one per byte.
    if let Some((first, rest)) = predicted.split_first_mut() {
        let mut before = *first;
        let mut blocks = rest.chunks_exact_mut(8);
        for block in &mut blocks {
            let mut sums = [0u8; 8];
            let mut sum = 0u8;
            for (s, d) in sums.iter_mut().zip(block.iter()) {
                sum = sum.wrapping_add(d.wrapping_sub(128));
                *s = sum;
            }
            for (b, s) in block.iter_mut().zip(sums) {
                *b = before.wrapping_add(s);
            }
            before = block[7];
        }
        for b in blocks.into_remainder() {
            *b = before.wrapping_add(b.wrapping_sub(128));
            before = *b;
        }
    }
    let (even, odd) = predicted.split_at(predicted.len().div_ceil(2));
    let mut raw = vec![0u8; predicted.len()];
    for ((pair, e), o) in raw.chunks_exact_mut(2).zip(even).zip(odd) {
        pair[0] = *e;
        pair[1] = *o;
    }
    if even.len() > odd.len() {
        if let (Some(last), Some(&e)) = (raw.last_mut(), even.last()) {
            *last = e;
        }
    }
    raw
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_predictor_is_openexrs() {
        // Bytes 1 2 3 4 5: even 1 3 5, odd 2 4; differences from 1.
        assert_eq!(predict(&[1, 2, 3, 4, 5]), vec![1, 130, 130, 125, 130]);
        assert_eq!(unpredict(&mut [1, 130, 130, 125, 130]), vec![1, 2, 3, 4, 5]);
    }

    #[test]
    fn bytes_come_back_as_they_were() {
        for length in [0usize, 1, 2, 3, 9, 16, 17, 25, 100] {
            let raw: Vec<u8> = (0..length).map(|i| (i * 37 % 256) as u8).collect();
            assert_eq!(unpredict(&mut predict(&raw)), raw, "{length}");
        }
    }
}
