//! Which Hesai model sent a packet, from its first bytes and length: how a reader picks the
//! decoder for a capture without `--sensor`. The decoder then checks every packet in full
//! against that model's format and refuses the others with the reason.

use super::model::Model;
use super::wire_fixed::{BLOCK_START, PANDAR40P};
use super::{wire, wire128};

/// The model whose packets begin like `bytes`: the 12-byte header's protocol version with its
/// laser and block counts, the Pandar64's 8-byte header, or the Pandar40P's block start and
/// length. Protocol 1.4 is taken for an OT128: the Pandar128 sends the same packets and
/// differs in firing times only.
pub fn identify(bytes: &[u8]) -> Option<Model> {
    let b = |i: usize| bytes.get(i).copied();
    if bytes.get(..2) == Some(&BLOCK_START[..]) {
        let extra = bytes.len().checked_sub(PANDAR40P.fixed_len())?;
        return PANDAR40P
            .extra
            .iter()
            .any(|(n, _)| *n == extra)
            .then_some(Model::Pandar40P);
    }
    if bytes.get(..2) != Some(&wire::START[..]) {
        return None;
    }
    let version = (b(2)?, b(3)?);
    if version == (64, 6) {
        return Some(Model::Pandar64);
    }
    let shape = (b(6)?, b(7)?);
    Some(match (version, shape) {
        (wire::VERSION, (32, 8)) => Model::Xt32,
        (wire::VERSION, (16, 8)) => Model::Xt16,
        (wire::VERSION, (32, 6)) => Model::Xt32m,
        (wire128::VERSION_QT, _) => Model::Qt128,
        (wire128::VERSION_128, _) => Model::Ot128,
        ((3, 1), (64, 4)) => Model::PandarQT64,
        ((4, 3), (128, 2)) => Model::At128,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headers_name_their_models() {
        let h = |v: [u8; 8]| {
            let mut p = [0u8; 1300];
            p[..8].copy_from_slice(&v);
            identify(&p)
        };
        assert_eq!(h([0xEE, 0xFF, 6, 1, 0, 0, 32, 8]), Some(Model::Xt32));
        assert_eq!(h([0xEE, 0xFF, 6, 1, 0, 0, 16, 8]), Some(Model::Xt16));
        assert_eq!(h([0xEE, 0xFF, 6, 1, 0, 0, 32, 6]), Some(Model::Xt32m));
        assert_eq!(h([0xEE, 0xFF, 3, 1, 0, 0, 64, 4]), Some(Model::PandarQT64));
        assert_eq!(h([0xEE, 0xFF, 64, 6, 0, 4, 0, 0]), Some(Model::Pandar64));
        assert_eq!(h([0xEE, 0xFF, 4, 3, 0, 0, 128, 2]), Some(Model::At128));
        assert_eq!(h([0xEE, 0xFF, 6, 1, 0, 0, 40, 8]), None);
        let mut p40 = [0u8; 1262];
        p40[..2].copy_from_slice(&BLOCK_START);
        assert_eq!(identify(&p40), Some(Model::Pandar40P));
        assert_eq!(identify(&p40[..1200]), None);
        assert_eq!(identify(&[0xEE]), None);
    }
}
