//! Deterministic byte mutations shared by the mutation tests of every reader (datasets in the plugin's tests;
//! images and meshes in the host's): bit flips, runs of extreme bytes, truncation, deletion, junk insertion and
//! little-endian integers of extreme size written over sizes, counts and offsets.
//! Included by `#[path]`, so the two crates share one mutator without a test-only crate.
#![allow(dead_code)]

/// The physics core's generator with a bounded draw.
pub struct Rng(pub firemedium_core::rng::Rng);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(firemedium_core::rng::Rng::new(seed))
    }
    pub fn next(&mut self) -> u64 {
        self.0.next_u64()
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// `src` with one to four mutations.
pub fn mutate(rng: &mut Rng, src: &[u8]) -> Vec<u8> {
    let mut b = src.to_vec();
    for _ in 0..1 + rng.below(4) {
        let n = b.len().max(1);
        match rng.below(6) {
            0 => {
                let i = rng.below(n);
                if i < b.len() {
                    b[i] ^= 1 << rng.below(8);
                }
            }
            1 => {
                // Overwrite 1–8 bytes with extreme values (sizes, counts, offsets).
                let i = rng.below(n);
                let v = [0x00u8, 0xff, 0x7f, 0x80][rng.below(4)];
                for k in i..(i + 1 + rng.below(8)).min(b.len()) {
                    b[k] = v;
                }
            }
            2 => b.truncate(rng.below(n)),
            3 => {
                let (i, j) = (rng.below(n), rng.below(n));
                let (i, j) = (i.min(j), i.max(j).min(b.len()));
                b.drain(i..j.min(i + 64));
            }
            4 => {
                let i = rng.below(n).min(b.len());
                let junk: Vec<u8> = (0..1 + rng.below(16)).map(|_| rng.next() as u8).collect();
                b.splice(i..i, junk);
            }
            _ => {
                // Write a little-endian i32/i64 at a random place.
                let i = rng.below(n);
                let v: i64 = [-1, 0, 1, i32::MAX as i64, i64::MAX, 1 << 33][rng.below(6)];
                for (k, byte) in v.to_le_bytes().iter().enumerate() {
                    if i + k < b.len() {
                        b[i + k] = *byte;
                    }
                }
            }
        }
    }
    b
}
