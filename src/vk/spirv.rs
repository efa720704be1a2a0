//! What a SPIR-V module declares, read from its words (SPIR-V spec 2.3, "Physical Layout"; 3.32, instructions):
//! names, decorations, types, constants, variables and execution modes. Passes take their descriptor set
//! layouts from it ([`descriptor_bindings`]), so a binding is declared once, in GLSL; tests/contracts.rs reads
//! struct offsets, attachment locations and workgroup sizes through it.
use super::descriptors::Binding;
use anyhow::{anyhow, bail, Result};
use ash::vk;
use std::collections::HashMap;

const OP_NAME: u32 = 5;
const OP_MEMBER_NAME: u32 = 6;
const OP_EXECUTION_MODE: u32 = 16;
const OP_TYPE_IMAGE: u32 = 25;
const OP_TYPE_SAMPLED_IMAGE: u32 = 27;
const OP_TYPE_ARRAY: u32 = 28;
const OP_TYPE_RUNTIME_ARRAY: u32 = 29;
pub const OP_TYPE_STRUCT: u32 = 30;
const OP_TYPE_POINTER: u32 = 32;
const OP_CONSTANT: u32 = 43;
const OP_VARIABLE: u32 = 59;
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;
const OP_EXECUTION_MODE_ID: u32 = 331;
const OP_TYPE_ACCELERATION_STRUCTURE: u32 = 5341;
const EXECUTION_MODE_LOCAL_SIZE: u32 = 17;
const EXECUTION_MODE_LOCAL_SIZE_ID: u32 = 38;
const DECORATION_LOCATION: u32 = 30;
const DECORATION_BINDING: u32 = 33;
const DECORATION_OFFSET: u32 = 35;
const STORAGE_UNIFORM_CONSTANT: u32 = 0;
pub const STORAGE_OUTPUT: u32 = 3;
const STORAGE_PUSH_CONSTANT: u32 = 9;
const STORAGE_STORAGE_BUFFER: u32 = 12;

/// One declared descriptor binding: the variable's name (or its block's), the Vulkan descriptor type it needs,
/// and its count (None for a runtime array, sized per set).
pub type Declared = (String, vk::DescriptorType, Option<u32>);

/// What strata reads of one module.
#[derive(Default, Debug)]
pub struct Module {
    pub names: HashMap<u32, String>,
    pub member_names: HashMap<(u32, u32), String>,
    pub member_offsets: HashMap<(u32, u32), u32>,
    pub bindings: HashMap<u32, u32>,
    pub locations: HashMap<u32, u32>,
    /// Result id → (opcode, operands after the result id).
    pub types: HashMap<u32, (u32, Vec<u32>)>,
    /// (variable id, pointer type id, storage class).
    pub variables: Vec<(u32, u32, u32)>,
    /// A compute shader's LocalSize execution mode, or the ids of its LocalSizeId (glslang's form when the size
    /// is a named constant): resolved through `constants` by `workgroup_size`.
    local_size: Option<[u32; 3]>,
    local_size_ids: Option<[u32; 3]>,
    /// 32-bit OpConstant values by result id.
    constants: HashMap<u32, u32>,
}

fn string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).take_while(|b| *b != 0).collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

/// Reads a module's words (little-endian bytes, as `ash::util::read_spv` reads them).
pub fn parse_bytes(bytes: &[u8]) -> Result<Module> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(bytes)).map_err(|e| anyhow!("not SPIR-V: {e}"))?;
    parse(&words)
}

pub fn parse(words: &[u32]) -> Result<Module> {
    if words.len() < 5 || words[0] != 0x0723_0203 {
        bail!("not SPIR-V (no magic number)");
    }
    let mut m = Module::default();
    let mut i = 5;
    while i < words.len() {
        let (count, op) = ((words[i] >> 16) as usize, words[i] & 0xffff);
        if count == 0 || i + count > words.len() {
            bail!("SPIR-V instruction at word {i} runs past the module's end");
        }
        let w = &words[i + 1..i + count];
        let operand = |k: usize| w.get(k).copied().ok_or_else(|| anyhow!("SPIR-V op {op} at word {i}: too short"));
        match op {
            OP_NAME => {
                m.names.insert(operand(0)?, string(&w[1..]));
            }
            OP_MEMBER_NAME => {
                m.member_names.insert((operand(0)?, operand(1)?), string(&w[2..]));
            }
            OP_DECORATE if operand(1)? == DECORATION_BINDING => {
                m.bindings.insert(operand(0)?, operand(2)?);
            }
            OP_DECORATE if operand(1)? == DECORATION_LOCATION => {
                m.locations.insert(operand(0)?, operand(2)?);
            }
            OP_MEMBER_DECORATE if operand(2)? == DECORATION_OFFSET => {
                m.member_offsets.insert((operand(0)?, operand(1)?), operand(3)?);
            }
            OP_VARIABLE => m.variables.push((operand(1)?, operand(0)?, operand(2)?)),
            OP_EXECUTION_MODE if operand(1)? == EXECUTION_MODE_LOCAL_SIZE => {
                m.local_size = Some([operand(2)?, operand(3)?, operand(4)?]);
            }
            OP_EXECUTION_MODE_ID if operand(1)? == EXECUTION_MODE_LOCAL_SIZE_ID => {
                m.local_size_ids = Some([operand(2)?, operand(3)?, operand(4)?]);
            }
            OP_CONSTANT if w.len() == 3 => {
                m.constants.insert(w[1], w[2]);
            }
            OP_TYPE_IMAGE
            | OP_TYPE_SAMPLED_IMAGE
            | OP_TYPE_ARRAY
            | OP_TYPE_RUNTIME_ARRAY
            | OP_TYPE_STRUCT
            | OP_TYPE_POINTER
            | OP_TYPE_ACCELERATION_STRUCTURE => {
                m.types.insert(operand(0)?, (op, w[1..].to_vec()));
            }
            _ => {}
        }
        i += count;
    }
    Ok(m)
}

impl Module {
    /// A compute shader's workgroup size, however the module states it.
    pub fn workgroup_size(&self) -> Option<[u32; 3]> {
        self.local_size.or_else(|| {
            let ids = self.local_size_ids?;
            Some([self.constants.get(&ids[0])?, self.constants.get(&ids[1])?, self.constants.get(&ids[2])?].map(|v| *v))
        })
    }

    /// The laid-out struct type named `name` (GLSL's struct or block name): glslang also emits an undecorated
    /// copy of a struct for local variables, which has no offsets.
    pub fn struct_named(&self, name: &str) -> Option<u32> {
        self.types
            .iter()
            .find(|(id, (op, _))| {
                *op == OP_TYPE_STRUCT
                    && self.names.get(id).map(String::as_str) == Some(name)
                    && self.member_offsets.contains_key(&(**id, 0))
            })
            .map(|(id, _)| *id)
    }

    /// Member name → offset of struct `id` (members without a name are `member K`, without an offset absent).
    pub fn offsets(&self, id: u32) -> HashMap<String, u32> {
        let members = self.types.get(&id).map_or(0, |t| t.1.len() as u32);
        (0..members)
            .filter_map(|k| {
                let name = self.member_names.get(&(id, k)).cloned().unwrap_or_else(|| format!("member {k}"));
                Some((name, *self.member_offsets.get(&(id, k))?))
            })
            .collect()
    }

    /// Strips pointers and arrays: the type a variable holds elements of.
    pub fn element(&self, mut id: u32) -> Option<u32> {
        loop {
            match self.types.get(&id)? {
                (OP_TYPE_POINTER, ops) => id = *ops.get(1)?,
                (OP_TYPE_ARRAY | OP_TYPE_RUNTIME_ARRAY, ops) => id = *ops.first()?,
                _ => return Some(id),
            }
        }
    }

    /// How many descriptors a variable of pointer type `pointer` holds: 1, an array's length, or None for a
    /// runtime array (sized per set).
    fn descriptor_count(&self, pointer: u32) -> Option<Option<u32>> {
        let pointee = *self.types.get(&pointer)?.1.get(1)?;
        Some(match self.types.get(&pointee) {
            Some((OP_TYPE_ARRAY, ops)) => Some(*self.constants.get(ops.get(1)?)?),
            Some((OP_TYPE_RUNTIME_ARRAY, _)) => None,
            _ => Some(1),
        })
    }

    /// Binding number → what the module declares there.
    pub fn descriptor_bindings(&self) -> Result<HashMap<u32, Declared>> {
        use vk::DescriptorType as D;
        let mut out = HashMap::new();
        for &(var, pointer, storage) in &self.variables {
            let Some(&binding) = self.bindings.get(&var) else { continue };
            let element =
                self.element(pointer).ok_or_else(|| anyhow!("binding {binding}: its type is not declared"))?;
            let name = self.names.get(&var).filter(|n| !n.is_empty()).or(self.names.get(&element)).cloned();
            let (op, ops) = &self.types[&element];
            let kind = match (storage, *op) {
                (STORAGE_UNIFORM_CONSTANT, OP_TYPE_ACCELERATION_STRUCTURE) => D::ACCELERATION_STRUCTURE_KHR,
                (STORAGE_UNIFORM_CONSTANT, OP_TYPE_SAMPLED_IMAGE) => D::COMBINED_IMAGE_SAMPLER,
                // Sampled 2 in OpTypeImage: a storage image.
                (STORAGE_UNIFORM_CONSTANT, OP_TYPE_IMAGE) if ops.get(5) == Some(&2) => D::STORAGE_IMAGE,
                (STORAGE_STORAGE_BUFFER, OP_TYPE_STRUCT) => D::STORAGE_BUFFER,
                other => bail!("binding {binding}: a kind of descriptor strata does not use: {other:?}"),
            };
            let count =
                self.descriptor_count(pointer).ok_or_else(|| anyhow!("binding {binding}: its type is not declared"))?;
            out.insert(binding, (name.unwrap_or_default(), kind, count));
        }
        Ok(out)
    }

    /// The push-constant block, where the stage reads one (the optimizer drops it from a stage that does not).
    pub fn push_constant_blocks(&self) -> Vec<u32> {
        self.variables.iter().filter(|v| v.2 == STORAGE_PUSH_CONSTANT).filter_map(|v| self.element(v.1)).collect()
    }
}

/// The descriptor set layout the stages `stages` (SPIR-V bytes, with their names for errors) declare together:
/// one binding per number, in order; a runtime array (the texture array) is variable-sized, up to
/// `variable_max`. Stages that declare one binding two ways are an error.
pub fn descriptor_bindings(stages: &[(&str, &[u8])], variable_max: u32) -> Result<Vec<Binding>> {
    let mut merged: std::collections::BTreeMap<u32, (&str, vk::DescriptorType, Option<u32>)> = Default::default();
    for &(stage, bytes) in stages {
        let module = parse_bytes(bytes).map_err(|e| anyhow!("{stage}: {e}"))?;
        let declared = module.descriptor_bindings().map_err(|e| anyhow!("{stage}: {e}"))?;
        for (binding, (_, kind, count)) in declared {
            match merged.get(&binding) {
                Some(&(other, k, c)) if (k, c) != (kind, count) => {
                    bail!("binding {binding}: {other} declares {k:?} x {c:?}, {stage} {kind:?} x {count:?}")
                }
                Some(_) => {}
                None => {
                    merged.insert(binding, (stage, kind, count));
                }
            }
        }
    }
    Ok(merged
        .into_iter()
        .map(|(binding, (_, kind, count))| match count {
            Some(n) => Binding::array(binding, kind, n),
            None => Binding::variable_array(binding, kind, variable_max.max(1)),
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truncated_or_foreign_words_are_errors_not_panics() {
        assert!(parse(&[1, 2, 3]).is_err());
        assert!(parse(&[0x0723_0203, 0, 0, 0, 0, (9 << 16) | OP_NAME, 1]).is_err(), "an instruction past the end");
        assert!(parse(&[0x0723_0203, 0, 0, 0, 0, (1 << 16) | OP_DECORATE]).is_err(), "a decoration without operands");
    }

    /// The resolve pass declares two storage images and a storage buffer, as resolve.comp says.
    #[test]
    fn the_resolve_shader_declares_its_three_bindings() {
        use crate::shaders::constants::*;
        let bindings = descriptor_bindings(&[("resolve.comp", crate::shaders::RESOLVE_COMP)], 1).unwrap();
        let kinds: Vec<(u32, vk::DescriptorType, u32)> =
            bindings.iter().map(|b| (b.binding, b.kind, b.count)).collect();
        assert_eq!(
            kinds,
            vec![
                (RESOLVE_BINDING_ACCUMULATION, vk::DescriptorType::STORAGE_IMAGE, 1),
                (RESOLVE_BINDING_DISPLAY, vk::DescriptorType::STORAGE_IMAGE, 1),
                (RESOLVE_BINDING_SUMS, vk::DescriptorType::STORAGE_BUFFER, 1),
            ]
        );
    }
}
