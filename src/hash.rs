//! FNV-1a (64-bit): a small, stable hash for fingerprints that must agree across runs, machines and builds
//! (std's hashers promise none of that). Fowler, Noll and Vo; parameters from the IETF draft
//! draft-eastlake-fnv.

/// An FNV-1a state; also a `fmt::Write`, so `write!(hash, "{:?}", value)` hashes a value's debug text without
/// building the string.
#[derive(Debug, Clone, Copy)]
pub struct Fnv1a(u64);

impl Default for Fnv1a {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv1a {
    pub fn update(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 ^= u64::from(*b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    pub fn finish(self) -> u64 {
        self.0
    }

    /// `fnv1a64:` and the hash in 16 hex digits.
    pub fn text(self) -> String {
        format!("fnv1a64:{:016x}", self.0)
    }
}

impl std::fmt::Write for Fnv1a {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.update(s.as_bytes());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        // From the FNV reference test vectors.
        assert_eq!(Fnv1a::default().finish(), 0xcbf2_9ce4_8422_2325);
        let mut h = Fnv1a::default();
        h.update(b"a");
        assert_eq!(h.finish(), 0xaf63_dc4c_8601_ec8c);
    }
}
