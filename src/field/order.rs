//! The vertex order: all vertices sorted by (value, id).
//!
//! Ties broken by id are what simulation of simplicity means on a grid, and
//! every sort here is *stable over ids*, so ties come out in id order without
//! comparing ids: counting sort for 8- and 16-bit values (O(n), one pass to
//! count, one to place), LSD radix sort on 32-bit keys, and a comparison sort
//! only for f64.

use super::Values;
use rayon::prelude::*;

/// The vertices sorted ascending by (value, id).
pub fn vertex_order(values: &Values) -> Vec<u32> {
    match values {
        Values::U8(v) => counting_sort(v.iter().map(|&x| x as usize), 1 << 8),
        Values::I8(v) => counting_sort(v.iter().map(|&x| (x as i16 + 128) as usize), 1 << 8),
        Values::U16(v) => counting_sort(v.iter().map(|&x| x as usize), 1 << 16),
        Values::I16(v) => counting_sort(v.iter().map(|&x| (x as i32 + 32768) as usize), 1 << 16),
        Values::U32(v) => radix_sort_u32_keys(v.iter().copied()),
        Values::I32(v) => radix_sort_u32_keys(v.iter().map(|&x| (x as u32) ^ 0x8000_0000)),
        Values::F32(v) => radix_sort_u32_keys(v.iter().map(|&x| f32_key(x))),
        Values::F64(v) => {
            let mut ids: Vec<u32> = (0..v.len() as u32).collect();
            ids.par_sort_unstable_by(|&a, &b| {
                v[a as usize].total_cmp(&v[b as usize]).then(a.cmp(&b))
            });
            // total_cmp orders -0.0 before 0.0; fix ties between them to id order.
            fix_signed_zero_ties(v, &mut ids);
            ids
        }
    }
}

/// Maps an f32 to a u32 whose unsigned order is the float order, with -0.0
/// and 0.0 mapped to the same key (they are equal values).
#[inline]
fn f32_key(x: f32) -> u32 {
    let x = if x == 0.0 { 0.0 } else { x };
    let b = x.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

fn counting_sort(keys: impl Iterator<Item = usize> + Clone, buckets: usize) -> Vec<u32> {
    let mut start = vec![0u32; buckets + 1];
    let mut n = 0usize;
    for k in keys.clone() {
        start[k + 1] += 1;
        n += 1;
    }
    for b in 1..=buckets {
        start[b] += start[b - 1];
    }
    let mut out = vec![0u32; n];
    for (i, k) in keys.enumerate() {
        let slot = &mut start[k];
        out[*slot as usize] = i as u32;
        *slot += 1;
    }
    out
}

/// Sorts ids by a 32-bit key with two stable 16-bit LSD passes over packed
/// (key << 32 | id) words.
fn radix_sort_u32_keys(keys: impl Iterator<Item = u32>) -> Vec<u32> {
    let mut a: Vec<u64> = keys
        .enumerate()
        .map(|(i, k)| ((k as u64) << 32) | i as u64)
        .collect();
    let mut b = vec![0u64; a.len()];
    for shift in [32u32, 48] {
        let mut start = vec![0usize; (1 << 16) + 1];
        for &w in &a {
            start[((w >> shift) & 0xffff) as usize + 1] += 1;
        }
        for d in 1..start.len() {
            start[d] += start[d - 1];
        }
        for &w in &a {
            let slot = &mut start[((w >> shift) & 0xffff) as usize];
            b[*slot] = w;
            *slot += 1;
        }
        std::mem::swap(&mut a, &mut b);
    }
    a.into_iter().map(|w| w as u32).collect()
}

fn fix_signed_zero_ties(v: &[f64], ids: &mut [u32]) {
    let mut i = 0;
    while i < ids.len() {
        if v[ids[i] as usize] == 0.0 {
            let mut j = i;
            while j < ids.len() && v[ids[j] as usize] == 0.0 {
                j += 1;
            }
            ids[i..j].sort_unstable();
            i = j;
        } else {
            i += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn by_comparison(values: &Values) -> Vec<u32> {
        let mut ids: Vec<u32> = (0..values.len() as u32).collect();
        ids.sort_by(|&a, &b| {
            values
                .get(a as usize)
                .partial_cmp(&values.get(b as usize))
                .expect("finite")
                .then(a.cmp(&b))
        });
        ids
    }

    #[test]
    fn every_type_sorts_by_value_then_id() {
        let raw: Vec<i64> = (0..500).map(|i| (i * 7919 % 23) - 11).collect();
        let all = [
            Values::U8(raw.iter().map(|&x| (x + 11) as u8).collect()),
            Values::I8(raw.iter().map(|&x| x as i8).collect()),
            Values::U16(raw.iter().map(|&x| (x * 1000 + 11000) as u16).collect()),
            Values::I16(raw.iter().map(|&x| (x * 1000) as i16).collect()),
            Values::U32(raw.iter().map(|&x| (x + 11) as u32 * 100_000).collect()),
            Values::I32(raw.iter().map(|&x| x as i32 * 100_000).collect()),
            Values::F32(raw.iter().map(|&x| x as f32 * 0.37).collect()),
            Values::F64(raw.iter().map(|&x| x as f64 * -1e-3).collect()),
        ];
        for values in &all {
            assert_eq!(
                vertex_order(values),
                by_comparison(values),
                "{}",
                values.type_name()
            );
        }
    }

    #[test]
    fn negative_zero_ties_with_zero_by_id() {
        let v = Values::F32(vec![0.0, -0.0, 1.0, -0.0, 0.0]);
        assert_eq!(vertex_order(&v), vec![0, 1, 3, 4, 2]);
        let v = Values::F64(vec![0.0, -0.0, 1.0, -0.0, 0.0]);
        assert_eq!(vertex_order(&v), vec![0, 1, 3, 4, 2]);
    }
}
