//! The shaders as the host sees them: the SPIR-V of every shader in `shaders/` (compiled by
//! build.rs and embedded in the binary, one `pub const NAME: &[u8]` each) and [`interface`], the
//! one declaration of every number and struct the host and the shaders share.
//!
//! To add a shared constant or a block field, edit the declaration in
//! `src/gpu/shaders/interface.rs`: the GLSL header `interface.glsl` and the Rust items both
//! follow from it.

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

// The Rust type of each GLSL type in the interface declaration.
include!("../../build-support/rust_type.rs");

/// Expands `interface.rs`'s declaration into Rust: the constants, the specialization-constant
/// struct and one `#[repr(C)]` Pod struct per block. build.rs expands the same declaration into
/// GLSL.
macro_rules! shader_interface {
    (
        constants {
            $( $(#[doc = $cdoc:literal])* $cname:ident : $cty:ty = $cvalue:expr; )*
        }
        specialization_constants {
            $(#[doc = $sdoc:literal])*
            struct $sname:ident { $( $(#[doc = $sfdoc:literal])* $sfield:ident ),* $(,)? }
        }
        blocks {
            $(
                $(#[doc = $bdoc:literal])*
                struct $bname:ident : $($rule:ident)+ {
                    $( $(#[doc = $fdoc:literal])* $field:ident : $fty:tt ),* $(,)?
                }
            )*
        }
    ) => {
        $( $(#[doc = $cdoc])* pub const $cname: $cty = $cvalue; )*

        $(#[doc = $sdoc])*
        #[repr(C)]
        #[derive(
            Clone, Copy, Debug, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable,
        )]
        pub struct $sname { $( $(#[doc = $sfdoc])* pub $sfield: u32, )* }

        $(
            $(#[doc = $bdoc])*
            #[repr(C)]
            #[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
            pub struct $bname { $( $(#[doc = $fdoc])* pub $field: rust_type!($fty), )* }
        )*

        /// Each block's Rust layout (name, size, field offsets), for the tests that hold it
        /// against the compiled SPIR-V.
        #[cfg(test)]
        pub(crate) const BLOCK_LAYOUTS: &[super::BlockLayout] = &[
            $(
                super::BlockLayout {
                    name: stringify!($bname),
                    size: std::mem::size_of::<$bname>(),
                    fields: &[ $( (stringify!($field), std::mem::offset_of!($bname, $field)) ),* ],
                },
            )*
        ];

        /// The specialization constants' names in GLSL, by `constant_id`.
        #[cfg(test)]
        pub(crate) const SPECIALIZATION_NAMES: &[&str] = &[ $( stringify!($sfield) ),* ];
    };
}

/// The GPU interface: limits, workgroup sizes, bindings, specialization constants and blocks,
/// declared once for Rust and GLSL (see the declaration's header comment).
pub mod interface;

impl interface::DrawConstants {
    /// The values as `VkSpecializationInfo` data: entry i is `constant_id` i.
    pub fn words(&self) -> &[u32] {
        bytemuck::cast_slice(std::slice::from_ref(self))
    }
}

/// A block's Rust layout: its name, size and (field, offset) list in declaration order.
#[cfg(test)]
pub(crate) struct BlockLayout {
    pub name: &'static str,
    pub size: usize,
    pub fields: &'static [(&'static str, usize)],
}

#[cfg(test)]
mod tests;
