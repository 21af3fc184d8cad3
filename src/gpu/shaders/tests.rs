//! The interface declaration held against what glslang compiled: every block's member offsets,
//! every specialization constant's id and every compute shader's workgroup size, read back from
//! the embedded SPIR-V (as kajiya reflects it), must be the Rust ones.

use super::interface::{BRDF_EVAL_WORKGROUP, PREFILTER_WORKGROUP};
use super::{interface, ALL};
use std::collections::HashMap;

const OP_NAME: u32 = 5;
const OP_MEMBER_NAME: u32 = 6;
const OP_EXECUTION_MODE: u32 = 16;
const OP_TYPE_STRUCT: u32 = 30;
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;
const EXECUTION_MODE_LOCAL_SIZE: u32 = 17;
const DECORATION_SPEC_ID: u32 = 1;
const DECORATION_OFFSET: u32 = 35;

/// What the tests read from one module.
#[derive(Default)]
struct Module {
    names: HashMap<u32, String>,
    member_names: HashMap<(u32, u32), String>,
    /// Struct type id → its member count.
    structs: HashMap<u32, usize>,
    offsets: HashMap<(u32, u32), u32>,
    spec_ids: HashMap<u32, u32>,
    local_size: Option<[u32; 3]>,
}

/// A SPIR-V literal string: UTF-8, NUL-terminated, in little-endian words.
fn string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    String::from_utf8_lossy(&bytes[..end]).into_owned()
}

fn parse(spirv: &[u8]) -> Module {
    let words: Vec<u32> = spirv
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    assert_eq!(words[0], 0x0723_0203, "not SPIR-V");
    let mut module = Module::default();
    let mut at = 5;
    while at < words.len() {
        let (count, opcode) = ((words[at] >> 16) as usize, words[at] & 0xffff);
        let operands = &words[at + 1..at + count];
        match opcode {
            OP_NAME => {
                module.names.insert(operands[0], string(&operands[1..]));
            }
            OP_MEMBER_NAME => {
                let key = (operands[0], operands[1]);
                module.member_names.insert(key, string(&operands[2..]));
            }
            OP_TYPE_STRUCT => {
                module.structs.insert(operands[0], operands.len() - 1);
            }
            OP_MEMBER_DECORATE if operands[2] == DECORATION_OFFSET => {
                module
                    .offsets
                    .insert((operands[0], operands[1]), operands[3]);
            }
            OP_DECORATE if operands[1] == DECORATION_SPEC_ID => {
                module.spec_ids.insert(operands[0], operands[2]);
            }
            OP_EXECUTION_MODE if operands[1] == EXECUTION_MODE_LOCAL_SIZE => {
                module.local_size = Some([operands[2], operands[3], operands[4]]);
            }
            _ => {}
        }
        at += count.max(1);
    }
    module
}

/// Each block has, in every shader that lays it out in memory, the Rust struct's members at the
/// Rust offsets, and at least one shader does.
#[test]
fn every_block_has_its_rust_layout_in_the_spirv() {
    for block in interface::BLOCK_LAYOUTS {
        let mut laid_out = Vec::new();
        for (shader, spirv) in ALL {
            let module = parse(spirv);
            for (&id, &members) in &module.structs {
                if module.names.get(&id).map(String::as_str) != Some(block.name)
                    || !module.offsets.contains_key(&(id, 0))
                {
                    continue;
                }
                let glsl: Vec<(&str, usize)> = (0..members as u32)
                    .map(|m| {
                        (
                            module.member_names[&(id, m)].as_str(),
                            module.offsets[&(id, m)] as usize,
                        )
                    })
                    .collect();
                assert_eq!(
                    glsl, block.fields,
                    "{} in {shader}: (member, offset) in SPIR-V vs Rust",
                    block.name
                );
                laid_out.push(*shader);
            }
        }
        assert!(
            !laid_out.is_empty(),
            "no shader lays out {} in memory: nothing checks its layout",
            block.name
        );
        assert!(block.size % 4 == 0, "{} is not whole words", block.name);
    }
}

/// A specialization constant's `constant_id` is its field's position in `DrawConstants`, and
/// its GLSL name is the field's in capitals.
#[test]
fn specialization_constants_have_their_field_positions_as_ids() {
    let mut seen = vec![false; interface::SPECIALIZATION_NAMES.len()];
    for (shader, spirv) in ALL {
        let module = parse(spirv);
        for (id, &constant_id) in &module.spec_ids {
            let name = &module.names[id];
            let field = interface::SPECIALIZATION_NAMES.get(constant_id as usize);
            assert_eq!(
                field.map(|f| f.to_uppercase()).as_ref(),
                Some(name),
                "{shader}: {name} has constant_id {constant_id}"
            );
            seen[constant_id as usize] = true;
        }
    }
    assert!(
        seen.iter().all(|&s| s),
        "a DrawConstants field no shader uses"
    );
}

/// Each compute shader's workgroup is the size the host dispatches by.
#[test]
fn compute_workgroups_are_the_declared_sizes() {
    for (shader, spirv) in ALL.iter().filter(|(name, _)| name.ends_with(".comp")) {
        let expected = match *shader {
            "brdf_eval.comp" | "brdf_environment_eval.comp" => [BRDF_EVAL_WORKGROUP, 1, 1],
            _ => [PREFILTER_WORKGROUP, PREFILTER_WORKGROUP, 1],
        };
        assert_eq!(parse(spirv).local_size, Some(expected), "{shader}");
    }
}
