//! `composite`: direct light plus caustics (Kim 2019, section 30.3.3).

use super::{bind, bytes, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::ImageBuf;

/// `out.rgb = direct.rgb + caustics.rgb`, `out.a = 1` (radiance, W/(sr m^2)).
#[derive(Clone, Copy, Debug)]
pub struct Composite {
    /// Direct-light radiance.
    pub direct: ImageBuf,
    /// Caustic radiance (the filtered caustics).
    pub caustics: ImageBuf,
    /// The sum.
    pub out: ImageBuf,
}

const BINDINGS: &[Binding] = &[
    bind("texels", Count),
    bind("direct", Read),
    bind("caustics", Read),
    bind("out", ReadWrite),
];

impl KernelDecl for Composite {
    const INFO: KernelInfo = KernelInfo::compute("composite", BINDINGS, "all");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let n = self.out.len as u64;
        a.count("texels", self.out.len)?
            .buf("direct", self.direct, n * bytes::IMAGE_TEXEL)?
            .buf("caustics", self.caustics, n * bytes::IMAGE_TEXEL)?
            .buf("out", self.out, n * bytes::IMAGE_TEXEL)?;
        Ok(Some(n))
    }
}
