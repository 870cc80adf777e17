//! OpenEXR's RLE chunks (`ImfRle`): runs of the
//! [`predictor`](super::predictor)'s bytes, a signed count before each: −n
//! for n bytes as they are, n for one byte n + 1 times.

use super::predictor::unpredict;

/// A compressed RLE chunk back to its `expected` bytes of samples.
pub(crate) fn decompress(data: &[u8], expected: usize) -> Result<Vec<u8>, String> {
    let damaged = || "an RLE chunk's runs do not make its lines".to_string();
    let mut predicted = Vec::with_capacity(expected);
    let mut rest = data;
    while let Some((&count, after)) = rest.split_first() {
        let count = count as i8;
        if count < 0 {
            let n = usize::from(count.unsigned_abs());
            let literal = after.get(..n).ok_or_else(damaged)?;
            predicted.extend_from_slice(literal);
            rest = &after[n..];
        } else {
            let (&byte, after) = after.split_first().ok_or_else(damaged)?;
            predicted.resize(predicted.len() + count as usize + 1, byte);
            rest = after;
        }
        if predicted.len() > expected {
            return Err(damaged());
        }
    }
    if predicted.len() != expected {
        return Err(damaged());
    }
    Ok(unpredict(&mut predicted))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::exr::predictor::predict;

    #[test]
    fn runs_and_literals_make_the_bytes() {
        let raw = [5u8, 5, 5, 9, 1, 2];
        let predicted = predict(&raw);
        // Every byte as a literal run.
        let mut data = vec![(-(predicted.len() as i8)) as u8];
        data.extend(&predicted);
        assert_eq!(decompress(&data, raw.len()).unwrap(), raw);
        // A repeat: one byte three times.
        let same = predict(&[7, 7, 7, 7, 7, 7]);
        assert_eq!(same[1..4], [128, 128, 128]);
        let data = [0u8, same[0], 4, 128];
        assert_eq!(decompress(&data, 6).unwrap(), vec![7; 6]);
        assert!(decompress(&data, 7).is_err());
        assert!(decompress(&[3], 4).is_err());
    }
}
