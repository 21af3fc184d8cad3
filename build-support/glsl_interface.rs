//! build.rs's half of the GPU interface: expands `src/gpu/shaders/interface.rs` (the one
//! declaration of what the host and the shaders share) into the GLSL header `interface.glsl`,
//! after checking that every block has the same layout in Rust (`#[repr(C)]`) as in GLSL under
//! the rules it declares. The library expands the same declaration into Rust (`gpu/shaders.rs`).

use std::fmt::Write as _;

/// Path of the declaration, relative to the package root.
pub const DECLARATION: &str = "src/gpu/shaders/interface.rs";

/// A GLSL type of the declaration: a base type or block name, or an array of one.
#[derive(PartialEq)]
pub enum Type {
    Named(&'static str),
    /// Element, length as written (a constant expression GLSL can read), length's value.
    Array(Box<Type>, &'static str, usize),
}

pub struct Constant {
    pub docs: &'static [&'static str],
    pub name: &'static str,
    pub value: String,
}

pub struct Specialization {
    pub docs: &'static [&'static str],
    pub name: &'static str,
    /// (field, docs, constant_id).
    pub fields: Vec<(&'static str, &'static [&'static str], usize)>,
}

pub struct Field {
    pub docs: &'static [&'static str],
    pub name: &'static str,
    pub ty: Type,
    /// Byte offset in the Rust struct.
    pub offset: usize,
}

pub struct Block {
    pub docs: &'static [&'static str],
    pub name: &'static str,
    /// Where GLSL uses the block: std140, std430, push_constant (std430 rules) and texels (read
    /// from an RGBA32F texel buffer, 16 bytes a texel).
    pub rules: &'static [&'static str],
    pub fields: Vec<Field>,
    /// size_of in Rust.
    pub size: usize,
}

pub struct Interface {
    pub constants: Vec<Constant>,
    pub specialization: Specialization,
    pub blocks: Vec<Block>,
}

/// An integer constant as GLSL reads it.
pub trait Integer {
    fn glsl(&self) -> String;
}

impl Integer for u32 {
    /// A value above `int`'s range is written as a `uint` literal, which GLSL needs for it.
    fn glsl(&self) -> String {
        match i32::try_from(*self) {
            Ok(_) => self.to_string(),
            Err(_) => format!("{self}u"),
        }
    }
}

impl Integer for usize {
    fn glsl(&self) -> String {
        self.to_string()
    }
}

impl Integer for i32 {
    fn glsl(&self) -> String {
        self.to_string()
    }
}

include!("rust_type.rs");

macro_rules! glsl_type {
    ([$element:tt; $len:expr]) => {
        super::Type::Array(Box::new(glsl_type!($element)), stringify!($len), $len)
    };
    ($name:ident) => {
        super::Type::Named(stringify!($name))
    };
}

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
        $( #[allow(dead_code)] pub const $cname: $cty = $cvalue; )*

        #[repr(C)]
        #[allow(dead_code)]
        struct $sname { $( $sfield: u32, )* }

        $(
            #[repr(C)]
            #[allow(dead_code)]
            struct $bname { $( $field: rust_type!($fty), )* }
        )*

        pub fn declaration() -> super::Interface {
            use super::Integer as _;
            super::Interface {
                constants: vec![
                    $( super::Constant {
                        docs: &[$($cdoc),*],
                        name: stringify!($cname),
                        value: $cname.glsl(),
                    }, )*
                ],
                specialization: super::Specialization {
                    docs: &[$($sdoc),*],
                    name: stringify!($sname),
                    fields: vec![
                        $( (
                            stringify!($sfield),
                            &[$($sfdoc),*],
                            std::mem::offset_of!($sname, $sfield) / 4,
                        ), )*
                    ],
                },
                blocks: vec![
                    $( super::Block {
                        docs: &[$($bdoc),*],
                        name: stringify!($bname),
                        rules: &[$(stringify!($rule)),+],
                        fields: vec![
                            $( super::Field {
                                docs: &[$($fdoc),*],
                                name: stringify!($field),
                                ty: glsl_type!($fty),
                                offset: std::mem::offset_of!($bname, $field),
                            }, )*
                        ],
                        size: std::mem::size_of::<$bname>(),
                    }, )*
                ],
            }
        }
    };
}

mod declared {
    include!("../src/gpu/shaders/interface.rs");
}

/// Alignment and size of a type under std140 (`std140 = true`) or std430.
fn layout_of(ty: &Type, std140: bool, blocks: &[Block]) -> Result<(usize, usize), String> {
    let round_up = |x: usize, a: usize| x.div_ceil(a) * a;
    Ok(match ty {
        Type::Named("float" | "int" | "uint") => (4, 4),
        Type::Named("vec3") => (16, 12),
        Type::Named("vec4" | "ivec4" | "uvec4") => (16, 16),
        Type::Named("mat4") => (16, 64),
        Type::Named(name) => {
            let block = blocks
                .iter()
                .find(|b| b.name == *name)
                .ok_or_else(|| format!("unknown type `{name}` (declare a block before its use)"))?;
            let offsets = block_offsets(block, std140, blocks)?;
            let mut align = 1;
            let mut end = 0;
            for (field, offset) in block.fields.iter().zip(offsets) {
                let (a, size) = layout_of(&field.ty, std140, blocks)?;
                align = align.max(a);
                end = offset + size;
            }
            if std140 {
                align = round_up(align, 16);
            }
            (align, round_up(end, align))
        }
        Type::Array(element, _, len) => {
            let (a, size) = layout_of(element, std140, blocks)?;
            let align = if std140 { round_up(a, 16) } else { a };
            (align, round_up(size, align) * len)
        }
    })
}

/// Each field's GLSL offset in `block` under std140 or std430.
fn block_offsets(block: &Block, std140: bool, blocks: &[Block]) -> Result<Vec<usize>, String> {
    let mut offset: usize = 0;
    let mut offsets = Vec::new();
    for field in &block.fields {
        let (align, size) = layout_of(&field.ty, std140, blocks)?;
        offset = offset.div_ceil(align) * align;
        offsets.push(offset);
        offset += size;
    }
    Ok(offsets)
}

/// Refuses a block whose Rust layout differs from its GLSL layout under any rule it declares.
fn check_block(block: &Block, blocks: &[Block]) -> Result<(), String> {
    for rule in block.rules {
        let std140 = match *rule {
            "std140" => true,
            "std430" | "push_constant" => false,
            "texels" => {
                check_texels(block)?;
                continue;
            }
            other => return Err(format!("{}: unknown rule `{other}`", block.name)),
        };
        for field in &block.fields {
            let mut ty = &field.ty;
            while let Type::Array(element, _, _) = ty {
                ty = element;
            }
            let nested = blocks.iter().find(|b| Type::Named(b.name) == *ty);
            if let Some(nested) = nested.filter(|b| !b.rules.contains(rule)) {
                return Err(format!(
                    "{}.{} is a {} under {rule}, which {} does not declare",
                    block.name, field.name, nested.name, nested.name
                ));
            }
        }
        let offsets = block_offsets(block, std140, blocks)?;
        for (field, glsl) in block.fields.iter().zip(&offsets) {
            if field.offset != *glsl {
                return Err(format!(
                    "{}.{} is at byte {} in Rust but {glsl} under {rule}: reorder the fields or \
                     pad them so both agree",
                    block.name, field.name, field.offset
                ));
            }
        }
        let (_, glsl_size) = layout_of(&Type::Named(block.name), std140, blocks)?;
        if glsl_size != block.size {
            return Err(format!(
                "{} is {} bytes in Rust but {glsl_size} under {rule}: pad it",
                block.name, block.size
            ));
        }
    }
    Ok(())
}

/// A texel block is whole RGBA32F texels of scalars, vec3s and vec4s, none across two texels.
fn check_texels(block: &Block) -> Result<(), String> {
    if block.size % 16 != 0 {
        return Err(format!(
            "{} (texels) is {} bytes, not whole texels",
            block.name, block.size
        ));
    }
    for field in &block.fields {
        let size = match field.ty {
            Type::Named("float" | "int" | "uint") => 4,
            Type::Named("vec3") => 12,
            Type::Named("vec4") => 16,
            _ => {
                return Err(format!(
                    "{}.{}: a texel block holds floats and vectors",
                    block.name, field.name
                ))
            }
        };
        if field.offset % 16 + size > 16 {
            return Err(format!(
                "{}.{} straddles two texels",
                block.name, field.name
            ));
        }
    }
    Ok(())
}

/// "ObjectMaterial" → "object_material".
fn snake_case(name: &str) -> String {
    let mut out = String::new();
    for (i, c) in name.chars().enumerate() {
        if c.is_ascii_uppercase() && i > 0 {
            out.push('_');
        }
        out.push(c.to_ascii_lowercase());
    }
    out
}

fn comment(out: &mut String, indent: &str, docs: &[&str]) {
    for line in docs {
        let _ = writeln!(out, "{indent}//{line}");
    }
}

fn glsl_field(ty: &Type, name: &str) -> String {
    match ty {
        Type::Named(base) => format!("{base} {name}"),
        Type::Array(element, len, _) => format!("{}[{len}]", glsl_field(element, name)),
    }
}

/// `NAME_TEXELS`, `name_from_texels(vec4 t0, …)` and `FETCH_NAME(buffer, index)`: the one
/// unpacking of a texel block, generated so that a field added in Rust is read in GLSL.
fn texel_functions(out: &mut String, block: &Block) {
    let snake = snake_case(block.name);
    let upper = snake.to_uppercase();
    let texels = block.size / 16;
    let _ = writeln!(out, "#define {upper}_TEXELS {texels}");
    let params: Vec<String> = (0..texels).map(|t| format!("vec4 t{t}")).collect();
    // The constructor's arguments, one line per texel.
    let mut rows = vec![Vec::new(); texels];
    for field in &block.fields {
        let components = match field.ty {
            Type::Named("vec3") => 3,
            Type::Named("vec4") => 4,
            _ => 1,
        };
        let first = field.offset % 16 / 4;
        let swizzle = &"xyzw"[first..first + components];
        rows[field.offset / 16].push(format!("t{}.{swizzle}", field.offset / 16));
    }
    let args: Vec<String> = rows.iter().map(|row| row.join(", ")).collect();
    let _ = writeln!(
        out,
        "{name} {snake}_from_texels({params}) {{\n    return {name}(\n        {args});\n}}",
        name = block.name,
        params = params.join(", "),
        args = args.join(",\n        "),
    );
    let fetches: Vec<String> = (0..texels)
        .map(|t| format!("texelFetch(buffer, {upper}_TEXELS * (index) + {t})"))
        .collect();
    let _ = writeln!(
        out,
        "// The `index`-th {name} of a textureBuffer of them.\n\
         #define FETCH_{upper}(buffer, index) {snake}_from_texels( \\\n    {fetches})",
        name = block.name,
        fetches = fetches.join(", \\\n    "),
    );
}

/// The checked declaration as the GLSL header.
pub fn header() -> Result<String, String> {
    let interface = declared::declaration();
    let mut out = format!(
        "// Generated by build.rs from {DECLARATION}: what the host and the shaders share.\n\
         // Edit the declaration there, not this file.\n\
         #ifndef SHIKKI_INTERFACE_GLSL\n#define SHIKKI_INTERFACE_GLSL\n\n"
    );
    for constant in &interface.constants {
        comment(&mut out, "", constant.docs);
        let _ = writeln!(out, "#define {} {}", constant.name, constant.value);
    }
    let spec = &interface.specialization;
    let _ = writeln!(
        out,
        "\n// {}: constant_id of each specialization constant.",
        spec.name
    );
    comment(&mut out, "", spec.docs);
    for (field, docs, id) in &spec.fields {
        comment(&mut out, "", docs);
        let _ = writeln!(out, "#define {}_ID {id}", field.to_uppercase());
    }
    for block in &interface.blocks {
        check_block(block, &interface.blocks).map_err(|e| format!("{DECLARATION}: {e}"))?;
        out.push('\n');
        comment(&mut out, "", block.docs);
        let _ = writeln!(out, "struct {} {{", block.name);
        for field in &block.fields {
            comment(&mut out, "    ", field.docs);
            let _ = writeln!(out, "    {};", glsl_field(&field.ty, field.name));
        }
        out.push_str("};\n");
        if block.rules.contains(&"texels") {
            texel_functions(&mut out, block);
        }
    }
    out.push_str("\n#endif\n");
    Ok(out)
}
