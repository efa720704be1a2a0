//! Specialization constants frozen into a module's words before the driver sees it, and the blocks that a
//! frozen branch condition can never reach taken out (SPIR-V spec 2.12 "Specialization", 2.11 "Structured
//! Control Flow"). The driver would fold the same branches itself, but only after turning the whole module into
//! its own IR, and the validation layer folds and validates the whole module again for every pipeline: a
//! validated 40×30 render of the Cornell box took 1.0–1.2 s from the whole module and 0.6–0.8 s from its
//! specialized blocks, a cost every process pays, warm cache or not (docs/performance.md, "Specialized before
//! the driver"). What runs is the same code: the pictures are the same bits.
//!
//! Only what strata's shaders use is understood (32-bit integer and boolean constants and the integer and
//! logical operations of `OpSpecConstantOp` below); a module with anything else is left to the driver whole.
use std::collections::{HashMap, HashSet, VecDeque};

const OP_NAME: u32 = 5;
const OP_TYPE_BOOL: u32 = 20;
const OP_CONSTANT_TRUE: u32 = 41;
const OP_CONSTANT_FALSE: u32 = 42;
const OP_CONSTANT: u32 = 43;
const OP_SPEC_CONSTANT_TRUE: u32 = 48;
const OP_SPEC_CONSTANT_FALSE: u32 = 49;
const OP_SPEC_CONSTANT: u32 = 50;
const OP_SPEC_CONSTANT_COMPOSITE: u32 = 51;
const OP_SPEC_CONSTANT_OP: u32 = 52;
const OP_FUNCTION: u32 = 54;
const OP_FUNCTION_END: u32 = 56;
const OP_DECORATE: u32 = 71;
const OP_DECORATE_ID: u32 = 332;
const OP_DECORATE_STRING: u32 = 5632;
const OP_PHI: u32 = 245;
const OP_LOOP_MERGE: u32 = 246;
const OP_SELECTION_MERGE: u32 = 247;
const OP_LABEL: u32 = 248;
const OP_BRANCH: u32 = 249;
const OP_BRANCH_CONDITIONAL: u32 = 250;
const OP_SWITCH: u32 = 251;
const OP_UNREACHABLE: u32 = 255;
const DECORATION_SPEC_ID: u32 = 1;

/// One instruction's words, its first word (count and opcode) included.
type Instruction = Vec<u32>;

fn opcode(instruction: &[u32]) -> u32 {
    instruction[0] & 0xffff
}

fn instruction(op: u32, operands: &[u32]) -> Instruction {
    let mut words = Vec::with_capacity(operands.len() + 1);
    words.push(((operands.len() as u32 + 1) << 16) | op);
    words.extend_from_slice(operands);
    words
}

/// `words` with the specialization constants `constant_id = i` set to `constants[i]` (the rest at their
/// defaults) and frozen into plain constants, and the blocks no frozen condition lets run removed. None when the
/// module has no specialization constants, or something this does not understand: the caller then hands the
/// driver the module whole, with its `VkSpecializationInfo`.
pub fn specialize(words: &[u32], constants: &[u32]) -> Option<Vec<u32>> {
    let mut module = parse(words)?;
    if !module.freeze(constants)? {
        return None;
    }
    let removed = module.prune_functions()?;
    module.drop_annotations_of(&removed);
    Some(module.words())
}

struct Module {
    header: [u32; 5],
    instructions: Vec<Instruction>,
    /// The value of every 32-bit integer and boolean constant (booleans as 0 or 1), by result id.
    values: HashMap<u32, u32>,
}

fn parse(words: &[u32]) -> Option<Module> {
    if words.len() < 5 || words[0] != 0x0723_0203 {
        return None;
    }
    let mut instructions = Vec::new();
    let mut i = 5;
    while i < words.len() {
        let count = (words[i] >> 16) as usize;
        if count == 0 || i + count > words.len() || count < least_words(words[i] & 0xffff) {
            return None;
        }
        instructions.push(words[i..i + count].to_vec());
        i += count;
    }
    let header = [words[0], words[1], words[2], words[3], words[4]];
    Some(Module { header, instructions, values: HashMap::new() })
}

/// The fewest words a valid instruction of the opcodes read here has (SPIR-V spec 3.32), so that reading its
/// operands cannot run past it; 1 for the rest.
fn least_words(op: u32) -> usize {
    match op {
        OP_NAME | OP_TYPE_BOOL | OP_LABEL | OP_BRANCH => 2,
        OP_CONSTANT_TRUE | OP_CONSTANT_FALSE | OP_SPEC_CONSTANT_TRUE | OP_SPEC_CONSTANT_FALSE => 3,
        OP_DECORATE | OP_DECORATE_ID | OP_DECORATE_STRING | OP_SELECTION_MERGE | OP_SWITCH | OP_PHI => 3,
        OP_CONSTANT | OP_SPEC_CONSTANT | OP_SPEC_CONSTANT_OP | OP_LOOP_MERGE | OP_BRANCH_CONDITIONAL => 4,
        _ => 1,
    }
}

/// `OpSpecConstantOp`'s operation on 32-bit integers and booleans (as 0 or 1); None for any other.
fn evaluate(operation: u32, a: &[u32]) -> Option<u32> {
    let arg = |k: usize| a.get(k).copied();
    let (x, y) = (arg(0)?, arg(1));
    Some(match operation {
        128 => x.wrapping_add(y?),                 // OpIAdd
        130 => x.wrapping_sub(y?),                 // OpISub
        132 => x.wrapping_mul(y?),                 // OpIMul
        164 | 170 => u32::from(x == y?),           // OpLogicalEqual, OpIEqual
        165 | 171 => u32::from(x != y?),           // OpLogicalNotEqual, OpINotEqual
        166 => u32::from(x != 0 || y? != 0),       // OpLogicalOr
        167 => u32::from(x != 0 && y? != 0),       // OpLogicalAnd
        168 => u32::from(x == 0),                  // OpLogicalNot
        169 => [y?, arg(2)?][usize::from(x == 0)], // OpSelect: the condition, then the two values
        172 => u32::from(x > y?),                  // OpUGreaterThan
        174 => u32::from(x >= y?),                 // OpUGreaterThanEqual
        176 => u32::from(x < y?),                  // OpULessThan
        178 => u32::from(x <= y?),                 // OpULessThanEqual
        197 => x | y?,                             // OpBitwiseOr
        198 => x ^ y?,                             // OpBitwiseXor
        199 => x & y?,                             // OpBitwiseAnd
        200 => !x,                                 // OpNot
        _ => return None,
    })
}

/// A function's blocks, in order: each from its `OpLabel` to its terminator.
struct Block {
    label: u32,
    instructions: Vec<Instruction>,
}

impl Block {
    /// The block's last instruction: its terminator in a valid module (its label if the module ends early).
    fn terminator(&self) -> &Instruction {
        &self.instructions[self.instructions.len() - 1]
    }

    /// The merge instruction before the terminator, if the block heads a construct.
    fn merge(&self) -> Option<&Instruction> {
        let n = self.instructions.len();
        (n >= 2).then(|| &self.instructions[n - 2]).filter(|i| matches!(opcode(i), OP_SELECTION_MERGE | OP_LOOP_MERGE))
    }

    fn successors(&self) -> Vec<u32> {
        let t = self.terminator();
        match opcode(t) {
            OP_BRANCH => vec![t[1]],
            OP_BRANCH_CONDITIONAL => vec![t[2], t[3]],
            // Selector, default, then (literal, label) pairs; strata's switches select on 32-bit values.
            OP_SWITCH => std::iter::once(t[2]).chain(t[3..].chunks(2).filter_map(|c| c.get(1).copied())).collect(),
            _ => Vec::new(),
        }
    }
}

impl Module {
    /// Freezes every specialization constant; false when the module has none, None when one cannot be.
    fn freeze(&mut self, constants: &[u32]) -> Option<bool> {
        let mut spec_ids = HashMap::new();
        for i in &self.instructions {
            if opcode(i) == OP_DECORATE && i.len() >= 4 && i[2] == DECORATION_SPEC_ID {
                spec_ids.insert(i[1], i[3]);
            }
        }
        let given = |id: u32| spec_ids.get(&id).and_then(|&k| constants.get(k as usize)).copied();
        let mut bools = HashSet::new();
        let mut froze = false;
        for i in &mut self.instructions {
            match opcode(i) {
                OP_TYPE_BOOL => {
                    bools.insert(i[1]);
                }
                OP_CONSTANT_TRUE | OP_CONSTANT_FALSE => {
                    self.values.insert(i[2], u32::from(opcode(i) == OP_CONSTANT_TRUE));
                }
                OP_CONSTANT if i.len() == 4 => {
                    self.values.insert(i[2], i[3]);
                }
                OP_SPEC_CONSTANT_TRUE | OP_SPEC_CONSTANT_FALSE => {
                    let value = given(i[2]).map_or(opcode(i) == OP_SPEC_CONSTANT_TRUE, |v| v != 0);
                    self.values.insert(i[2], u32::from(value));
                    *i = instruction(if value { OP_CONSTANT_TRUE } else { OP_CONSTANT_FALSE }, &[i[1], i[2]]);
                    froze = true;
                }
                OP_SPEC_CONSTANT => {
                    if i.len() != 4 {
                        return None; // a 64-bit constant
                    }
                    let value = given(i[2]).unwrap_or(i[3]);
                    self.values.insert(i[2], value);
                    *i = instruction(OP_CONSTANT, &[i[1], i[2], value]);
                    froze = true;
                }
                OP_SPEC_CONSTANT_OP => {
                    let operands = i[4..].iter().map(|id| self.values.get(id).copied()).collect::<Option<Vec<_>>>()?;
                    let value = evaluate(i[3], &operands)?;
                    self.values.insert(i[2], value);
                    *i = if bools.contains(&i[1]) {
                        instruction(if value != 0 { OP_CONSTANT_TRUE } else { OP_CONSTANT_FALSE }, &[i[1], i[2]])
                    } else {
                        instruction(OP_CONSTANT, &[i[1], i[2], value])
                    };
                    froze = true;
                }
                OP_SPEC_CONSTANT_COMPOSITE => return None,
                _ => {}
            }
        }
        // A SpecId on what is now a plain constant is invalid.
        self.instructions.retain(|i| !(opcode(i) == OP_DECORATE && i.len() >= 3 && i[2] == DECORATION_SPEC_ID));
        Some(froze)
    }

    /// Every function's branches on a known condition made unconditional, and the blocks no longer reached
    /// removed; returns every word of the instructions removed.
    fn prune_functions(&mut self) -> Option<HashSet<u32>> {
        let mut removed = HashSet::new();
        let mut out = Vec::with_capacity(self.instructions.len());
        let mut rest = std::mem::take(&mut self.instructions).into_iter();
        while let Some(i) = rest.next() {
            if opcode(&i) != OP_FUNCTION {
                out.push(i);
                continue;
            }
            // The function's own instructions and parameters, then its blocks.
            out.push(i);
            let mut blocks: Vec<Block> = Vec::new();
            for i in rest.by_ref() {
                match opcode(&i) {
                    OP_FUNCTION_END => {
                        let blocks = self.prune(blocks, &mut removed)?;
                        out.extend(blocks.into_iter().flat_map(|b| b.instructions));
                        out.push(i);
                        break;
                    }
                    OP_LABEL => blocks.push(Block { label: i[1], instructions: vec![i] }),
                    _ => match blocks.last_mut() {
                        Some(block) => block.instructions.push(i),
                        None => out.push(i), // OpFunctionParameter
                    },
                }
            }
        }
        self.instructions = out;
        Some(removed)
    }

    fn prune(&self, mut blocks: Vec<Block>, removed: &mut HashSet<u32>) -> Option<Vec<Block>> {
        if blocks.is_empty() {
            return Some(blocks); // a declaration
        }
        self.fold_known_branches(&mut blocks);
        let index: HashMap<u32, usize> = blocks.iter().enumerate().map(|(k, b)| (b.label, k)).collect();
        let reached = reached_from_entry(&blocks, &index)?;
        let merges = unreached_merges(&blocks, &index, &reached)?;
        let mut kept = Vec::with_capacity(blocks.len());
        for (k, mut block) in blocks.into_iter().enumerate() {
            let words_of = |i: Instruction| i.into_iter().skip(1);
            if reached[k] {
                kept.push(block);
            } else if merges.contains(&k) {
                removed.extend(block.instructions.drain(1..).flat_map(words_of));
                block.instructions.push(instruction(OP_UNREACHABLE, &[]));
                kept.push(block);
            } else {
                removed.extend(block.instructions.into_iter().flat_map(words_of));
            }
        }
        keep_phi_operands_of_edges_left(&mut kept)?;
        Some(kept)
    }

    /// A selection whose condition is known becomes a branch to the side taken, without its merge (as spirv-opt's
    /// dead-branch elimination does), and so does a conditional break or continue. Loop headers keep their
    /// conditions: the driver folds those.
    fn fold_known_branches(&self, blocks: &mut [Block]) {
        for block in blocks {
            let t = block.terminator();
            if opcode(t) != OP_BRANCH_CONDITIONAL {
                continue;
            }
            let Some(&value) = self.values.get(&t[1]) else { continue };
            let taken = if value != 0 { t[2] } else { t[3] };
            let merge = block.merge().map(|m| opcode(m));
            if merge == Some(OP_LOOP_MERGE) {
                continue;
            }
            let n = block.instructions.len();
            block.instructions.truncate(if merge.is_some() { n - 2 } else { n - 1 });
            block.instructions.push(instruction(OP_BRANCH, &[taken]));
        }
    }

    /// Drops the names and decorations of ids that only the removed instructions held (`removed`: their words).
    /// A result defined in a removed block is used only in blocks it dominates, all removed with it, so an id
    /// that no kept instruction holds is gone.
    fn drop_annotations_of(&mut self, removed: &HashSet<u32>) {
        let annotation = |i: &[u32]| matches!(opcode(i), OP_NAME | OP_DECORATE | OP_DECORATE_ID | OP_DECORATE_STRING);
        let held: HashSet<u32> =
            self.instructions.iter().filter(|i| !annotation(i)).flat_map(|i| i[1..].iter().copied()).collect();
        self.instructions.retain(|i| !annotation(i) || !removed.contains(&i[1]) || held.contains(&i[1]));
    }

    fn words(&self) -> Vec<u32> {
        let mut words = self.header.to_vec();
        for i in &self.instructions {
            words.extend_from_slice(i);
        }
        words
    }
}

/// Which blocks the entry block's branches reach.
fn reached_from_entry(blocks: &[Block], index: &HashMap<u32, usize>) -> Option<Vec<bool>> {
    let mut reached = vec![false; blocks.len()];
    let mut queue = VecDeque::from([0usize]);
    reached[0] = true;
    while let Some(k) = queue.pop_front() {
        for next in blocks[k].successors() {
            let j = *index.get(&next)?;
            if !reached[j] {
                reached[j] = true;
                queue.push_back(j);
            }
        }
    }
    Some(reached)
}

/// The unreached merge blocks that reached headers name: they stay, as `OpUnreachable` blocks (as spirv-opt
/// keeps them). None if a reached loop's continue target is unreached: that would take a back edge to the header
/// and phi operands for it, which strata's shaders never need.
fn unreached_merges(blocks: &[Block], index: &HashMap<u32, usize>, reached: &[bool]) -> Option<HashSet<usize>> {
    let mut merges = HashSet::new();
    for (k, block) in blocks.iter().enumerate() {
        let Some(merge) = block.merge().filter(|_| reached[k]) else { continue };
        let j = *index.get(&merge[1])?;
        if !reached[j] {
            merges.insert(j);
        }
        if opcode(merge) == OP_LOOP_MERGE && !reached[*index.get(&merge[2])?] {
            return None;
        }
    }
    Some(merges)
}

/// Each phi keeps the operands of the edges into its block that are left. A result defined in a removed block
/// dominated every block that used it, so none of the operands kept names one.
fn keep_phi_operands_of_edges_left(blocks: &mut [Block]) -> Option<()> {
    let mut predecessors: HashMap<u32, HashSet<u32>> = HashMap::new();
    for block in blocks.iter() {
        for next in block.successors() {
            predecessors.entry(next).or_default().insert(block.label);
        }
    }
    for block in blocks {
        let from = predecessors.get(&block.label);
        for i in block.instructions.iter_mut().filter(|i| opcode(i) == OP_PHI) {
            let pairs = i[3..].chunks(2).filter(|pair| pair.len() == 2 && from.is_some_and(|f| f.contains(&pair[1])));
            let mut operands = vec![i[1], i[2]];
            operands.extend(pairs.flatten());
            if operands.len() == 2 {
                return None;
            }
            *i = instruction(OP_PHI, &operands);
        }
    }
    Some(())
}
