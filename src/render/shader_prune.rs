//! Specialisation done before the driver sees the shader: the pipeline's `override` constants are substituted; a
//! call to a function that returns a constant (`cfg_mode()` once `SPEC_MODE` is fixed) becomes that constant; every
//! `if` and `switch` whose condition is then constant becomes the branch it takes; and whatever no remaining
//! statement calls is dropped. The driver compiles only code that a sample can run.
//!
//! Why: naga hands the driver every function the entry point can reach through any branch, with the settings as
//! opaque values until the driver folds them. lavapipe inlines that whole call tree before it folds the constant
//! branches away, and the render kernel's compilation — the seconds of every run's start-up — grows with it
//! (`docs/performance.md`, "Time to an image"). Nothing here changes what a kept statement computes, so the image is
//! the same bit for bit (`tests/shader_prune.rs`).

use naga::{BinaryOperator, Block, Expression, Function, Handle, Literal, Module, Statement, SwitchValue};
use std::collections::{HashMap, HashSet};

/// `module` (valid) specialised to `constants` for compute entry point `entry` and pruned, written back as WGSL
/// without overrides (for any backend, WebGPU's included).
pub fn specialized_wgsl(module: &Module, entry: &str, constants: &[(&str, f64)]) -> Result<String, String> {
    let mut validator =
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all());
    let info = validator.validate(module).map_err(|e| format!("{e:?}"))?;
    let constants: naga::back::PipelineConstants = constants.iter().map(|(k, v)| (k.to_string(), *v)).collect();
    let (module, _) = naga::back::pipeline_constants::process_overrides(
        module,
        &info,
        Some((naga::ShaderStage::Compute, entry)),
        &constants,
    )
    .map_err(|e| format!("override constants: {e}"))?;
    let mut module = module.into_owned();
    prune(&mut module);
    let info = validator.validate(&module).map_err(|e| format!("the pruned module does not validate: {e:?}"))?;
    let wgsl = naga::back::wgsl::write_string(&module, &info, naga::back::wgsl::WriterFlags::empty())
        .map_err(|e| format!("writing the pruned module: {e}"))?;
    // naga writes f32::MAX as its shortest decimal, 3.4028235e38, which lies above f32::MAX: naga reads it back, but
    // Chromium's WGSL compiler (Tint) refuses it as out of range. Its exact hexadecimal form is the same value.
    Ok(wgsl.replace("340282350000000000000000000000000000000f", "0x1.fffffep+127f"))
}

/// Folds constant calls and branches in every function (callees first: naga orders functions before their
/// callers), then drops what is unreferenced.
pub fn prune(module: &mut Module) {
    let globals: HashMap<Handle<naga::Constant>, Literal> = module
        .constants
        .iter()
        .filter_map(|(h, c)| match module.global_expressions[c.init] {
            Expression::Literal(l) => Some((h, l)),
            _ => None,
        })
        .collect();
    let mut constant_functions = HashMap::new();
    let handles: Vec<_> = module.functions.iter().map(|(h, _)| h).collect();
    for h in handles {
        let f = &mut module.functions[h];
        if let Some(value) = fold_function(f, &module.types, &globals, &constant_functions) {
            constant_functions.insert(h, value);
        }
    }
    for ep in module.entry_points.iter_mut() {
        fold_function(&mut ep.function, &module.types, &globals, &constant_functions);
    }
    naga::compact::compact(module, naga::compact::KeepUnused::No);
}

/// Calls of constant functions become their value; constant branches become the branch taken. Returns the value the
/// function returns where that is a constant.
fn fold_function(
    f: &mut Function,
    types: &naga::UniqueArena<naga::Type>,
    globals: &HashMap<Handle<naga::Constant>, Literal>,
    constant_functions: &HashMap<Handle<Function>, Literal>,
) -> Option<Literal> {
    fold_calls(&mut f.body, &mut f.expressions, constant_functions);
    let locals = SimpleLocals::of(f, types);
    let mut eval = Eval { exprs: &f.expressions, globals, locals: &locals, loaded: HashMap::new() };
    let mut known = locals.initial.clone();
    let mut removed = Vec::new();
    prune_block(&mut f.body, &mut eval, &mut known, &mut removed);
    // Compaction keeps every named expression alive; those only the removed code defined must go with it.
    let removed: HashSet<_> = removed.into_iter().collect();
    f.named_expressions.retain(|h, _| !removed.contains(h));
    constant_return(&f.body, &eval)
}

/// The boolean local variables whose value a walk in program order can know: reached only by loads and stores of
/// the variable itself (no pointer to them passed on or indexed). naga lowers `a && b` to such a variable, set in
/// an `if` on `a`, so `HAS_X && kind == K` folds once `HAS_X` is false.
struct SimpleLocals {
    /// The expression that names each such variable.
    by_expression: HashMap<Handle<Expression>, Handle<naga::LocalVariable>>,
    /// Their values at the function's start (WGSL zero-initialises a variable without an initialiser).
    initial: HashMap<Handle<naga::LocalVariable>, Literal>,
}

impl SimpleLocals {
    fn of(f: &Function, types: &naga::UniqueArena<naga::Type>) -> Self {
        let is_bool = |ty: Handle<naga::Type>| {
            matches!(types[ty].inner, naga::TypeInner::Scalar(naga::Scalar { kind: naga::ScalarKind::Bool, .. }))
        };
        let mut by_expression: HashMap<_, _> = f
            .expressions
            .iter()
            .filter_map(|(h, e)| match *e {
                Expression::LocalVariable(v) if is_bool(f.local_variables[v].ty) => Some((h, v)),
                _ => None,
            })
            .collect();
        // Any use but a load's pointer or a store's pointer disqualifies (calls' arguments are checked below).
        let mut escaped = HashSet::new();
        for (_, e) in f.expressions.iter() {
            if !matches!(e, Expression::Load { .. } | Expression::LocalVariable(_)) {
                let mut note = |h: Handle<Expression>| {
                    escaped.insert(h);
                };
                expression_operands(e, &mut note);
            }
        }
        calls_arguments(&f.body, &mut escaped);
        by_expression.retain(|h, _| !escaped.contains(h));
        let initial = by_expression
            .values()
            .map(|&v| {
                let init = f.local_variables[v].init.and_then(|i| match f.expressions[i] {
                    Expression::Literal(l) => Some(l),
                    _ => None,
                });
                (v, init.unwrap_or(Literal::Bool(false)))
            })
            .collect();
        SimpleLocals { by_expression, initial }
    }

    fn variable(&self, pointer: Handle<Expression>) -> Option<Handle<naga::LocalVariable>> {
        self.by_expression.get(&pointer).copied()
    }
}

/// The operands of an expression that could be pointers (enough to find where a local variable's pointer goes).
fn expression_operands(e: &Expression, note: &mut impl FnMut(Handle<Expression>)) {
    match *e {
        Expression::Access { base, index } => {
            note(base);
            note(index);
        }
        Expression::AccessIndex { base, .. } => note(base),
        Expression::Load { pointer } => note(pointer),
        Expression::Select { condition, accept, reject } => {
            note(condition);
            note(accept);
            note(reject);
        }
        Expression::Binary { left, right, .. } => {
            note(left);
            note(right);
        }
        Expression::Unary { expr, .. }
        | Expression::As { expr, .. }
        | Expression::Relational { argument: expr, .. } => note(expr),
        Expression::Compose { ref components, .. } => components.iter().for_each(|&c| note(c)),
        Expression::Splat { value, .. } => note(value),
        Expression::Swizzle { vector, .. } => note(vector),
        Expression::Math { arg, arg1, arg2, arg3, .. } => {
            note(arg);
            [arg1, arg2, arg3].into_iter().flatten().for_each(|a| note(a));
        }
        Expression::ArrayLength(a) => note(a),
        _ => {}
    }
}

/// Notes every expression passed to a call, in every block.
fn calls_arguments(block: &Block, out: &mut HashSet<Handle<Expression>>) {
    for stmt in block.iter() {
        match stmt {
            Statement::Call { arguments, .. } => out.extend(arguments.iter().copied()),
            Statement::Atomic { pointer, .. } => {
                out.insert(*pointer);
            }
            Statement::Block(b) => calls_arguments(b, out),
            Statement::If { accept, reject, .. } => {
                calls_arguments(accept, out);
                calls_arguments(reject, out);
            }
            Statement::Switch { cases, .. } => cases.iter().for_each(|c| calls_arguments(&c.body, out)),
            Statement::Loop { body, continuing, .. } => {
                calls_arguments(body, out);
                calls_arguments(continuing, out);
            }
            _ => {}
        }
    }
}

/// Replaces each call of a constant function by its value: the call's result expression becomes the literal (it
/// needs no emitting) and the call statement an empty block. Such functions have no side effects (see
/// `constant_return`).
fn fold_calls(
    block: &mut Block,
    exprs: &mut naga::Arena<Expression>,
    constant_functions: &HashMap<Handle<Function>, Literal>,
) {
    for stmt in block.iter_mut() {
        match stmt {
            Statement::Call { function, result, .. } => {
                if let Some(value) = constant_functions.get(function) {
                    if let Some(r) = *result {
                        exprs[r] = Expression::Literal(*value);
                    }
                    *stmt = Statement::Block(Block::new());
                }
            }
            _ => for_each_child(stmt, |b| fold_calls(b, exprs, constant_functions)),
        }
    }
}

/// Calls `f` on every block directly inside `stmt`.
fn for_each_child(stmt: &mut Statement, mut f: impl FnMut(&mut Block)) {
    match stmt {
        Statement::Block(b) => f(b),
        Statement::If { accept, reject, .. } => {
            f(accept);
            f(reject);
        }
        Statement::Switch { cases, .. } => cases.iter_mut().for_each(|c| f(&mut c.body)),
        Statement::Loop { body, continuing, .. } => {
            f(body);
            f(continuing);
        }
        _ => {}
    }
}

/// The value a function body returns when it is only expressions, stores to its simple locals and one `return`
/// of a constant: no calls, no branches left, nothing written outside the function.
fn constant_return(body: &Block, eval: &Eval) -> Option<Literal> {
    for stmt in body.iter() {
        match stmt {
            Statement::Return { value: Some(v) } => return eval.literal(*v),
            Statement::Block(b) => {
                if let Some(v) = constant_return(b, eval) {
                    return Some(v);
                }
                if !pure(b, eval) {
                    return None;
                }
            }
            s if pure_statement(s, eval) => {}
            _ => return None,
        }
    }
    None
}

/// Whether a block only computes expressions and stores to the function's simple locals.
fn pure(block: &Block, eval: &Eval) -> bool {
    block.iter().all(|s| pure_statement(s, eval))
}

fn pure_statement(s: &Statement, eval: &Eval) -> bool {
    match s {
        Statement::Emit(_) => true,
        Statement::Store { pointer, .. } => eval.locals.variable(*pointer).is_some(),
        Statement::Block(b) => pure(b, eval),
        _ => false,
    }
}

/// Constant folding of the expressions that settings and features build: literals, constants, comparisons,
/// logic and bit operations on them, and `select` with a constant condition.
struct Eval<'a> {
    exprs: &'a naga::Arena<Expression>,
    globals: &'a HashMap<Handle<naga::Constant>, Literal>,
    locals: &'a SimpleLocals,
    /// Loads of simple locals whose value was known where they were emitted.
    loaded: HashMap<Handle<Expression>, Literal>,
}

impl Eval<'_> {
    fn literal(&self, h: Handle<Expression>) -> Option<Literal> {
        match self.exprs[h] {
            Expression::Literal(l) => Some(l),
            Expression::Constant(c) => self.globals.get(&c).copied(),
            Expression::Load { .. } => self.loaded.get(&h).copied(),
            Expression::Select { condition, accept, reject } => match self.literal(condition)? {
                Literal::Bool(true) => self.literal(accept),
                Literal::Bool(false) => self.literal(reject),
                _ => None,
            },
            Expression::Unary { op: naga::UnaryOperator::LogicalNot, expr } => match self.literal(expr)? {
                Literal::Bool(b) => Some(Literal::Bool(!b)),
                _ => None,
            },
            Expression::Binary { op, left, right } => self.binary(op, left, right),
            _ => None,
        }
    }

    fn binary(&self, op: BinaryOperator, left: Handle<Expression>, right: Handle<Expression>) -> Option<Literal> {
        use BinaryOperator as B;
        let (l, r) = (self.literal(left), self.literal(right));
        // `false && x` and `true || x` whatever x is (an expression has no side effects).
        match (op, l, r) {
            (B::LogicalAnd, Some(Literal::Bool(false)), _) | (B::LogicalAnd, _, Some(Literal::Bool(false))) => {
                return Some(Literal::Bool(false));
            }
            (B::LogicalOr, Some(Literal::Bool(true)), _) | (B::LogicalOr, _, Some(Literal::Bool(true))) => {
                return Some(Literal::Bool(true));
            }
            _ => {}
        }
        match (l?, r?) {
            (Literal::Bool(a), Literal::Bool(b)) => match op {
                B::LogicalAnd | B::And => Some(Literal::Bool(a && b)),
                B::LogicalOr | B::InclusiveOr => Some(Literal::Bool(a || b)),
                B::Equal => Some(Literal::Bool(a == b)),
                B::NotEqual | B::ExclusiveOr => Some(Literal::Bool(a != b)),
                _ => None,
            },
            (Literal::U32(a), Literal::U32(b)) => integer(op, a, b).map(|v| v.map_or_else(Literal::Bool, Literal::U32)),
            (Literal::I32(a), Literal::I32(b)) => integer(op, a, b).map(|v| v.map_or_else(Literal::Bool, Literal::I32)),
            _ => None,
        }
    }
}

/// An integer operation: Ok(value) or, for a comparison, Err(truth) (so one match serves u32 and i32).
fn integer<T>(op: BinaryOperator, a: T, b: T) -> Option<Result<T, bool>>
where
    T: Ord + Copy + std::ops::BitAnd<Output = T> + std::ops::BitOr<Output = T> + std::ops::BitXor<Output = T>,
{
    use BinaryOperator as B;
    Some(match op {
        B::Equal => Err(a == b),
        B::NotEqual => Err(a != b),
        B::Less => Err(a < b),
        B::LessEqual => Err(a <= b),
        B::Greater => Err(a > b),
        B::GreaterEqual => Err(a >= b),
        B::And => Ok(a & b),
        B::InclusiveOr => Ok(a | b),
        B::ExclusiveOr => Ok(a ^ b),
        _ => return None,
    })
}

/// What a walk in program order knows of the simple locals' values.
type Known = HashMap<Handle<naga::LocalVariable>, Literal>;

/// Prunes `block` in place, walking it in program order; `removed` gathers the expressions that the removed
/// branches defined.
fn prune_block(block: &mut Block, eval: &mut Eval, known: &mut Known, removed: &mut Vec<Handle<Expression>>) {
    let mut end = block.len();
    for (index, stmt) in block.iter_mut().enumerate() {
        let taken = match stmt {
            Statement::Emit(range) => {
                for h in range.clone() {
                    if let Expression::Load { pointer } = eval.exprs[h] {
                        if let Some(v) = eval.locals.variable(pointer).and_then(|v| known.get(&v)) {
                            eval.loaded.insert(h, *v);
                        }
                    }
                }
                None
            }
            Statement::Store { pointer, value } => {
                if let Some(v) = eval.locals.variable(*pointer) {
                    match eval.literal(*value) {
                        Some(l) => known.insert(v, l),
                        None => known.remove(&v),
                    };
                }
                None
            }
            Statement::If { condition, accept, reject } => match eval.literal(*condition) {
                Some(Literal::Bool(b)) => {
                    let (taken, dropped) = if b { (accept, reject) } else { (reject, accept) };
                    defined_in(dropped, removed);
                    Some(std::mem::take(taken))
                }
                _ => None,
            },
            Statement::Switch { selector, cases } => {
                eval.literal(*selector).and_then(|v| taken_case(v, cases, removed))
            }
            _ => None,
        };
        match taken {
            // A branch known to be taken runs in line: what is known flows through it.
            Some(mut b) => {
                prune_block(&mut b, eval, known, removed);
                *stmt = Statement::Block(b);
            }
            None => match stmt {
                Statement::Block(b) => prune_block(b, eval, known, removed),
                Statement::If { accept, reject, .. } => {
                    // Both branches start from what is known before; after, a variable is known where every
                    // branch that falls through leaves it the same (`a && B` with B false sets false either way).
                    let (mut after_accept, mut after_reject) = (known.clone(), known.clone());
                    prune_block(accept, eval, &mut after_accept, removed);
                    prune_block(reject, eval, &mut after_reject, removed);
                    *known = match (accept.last().is_some_and(terminates), reject.last().is_some_and(terminates)) {
                        (true, false) => after_reject,
                        (false, true) => after_accept,
                        _ => {
                            after_accept.retain(|v, l| after_reject.get(v) == Some(l));
                            after_accept
                        }
                    };
                }
                Statement::Switch { .. } | Statement::Loop { .. } => {
                    // Each case (or iteration) starts from what is known before it, less what a loop's own body
                    // may change; after it, nothing it stores to is known.
                    let mut stored = HashSet::new();
                    for_each_child(stmt, |b| stored_in(b, eval.locals, &mut stored));
                    let mut entry = known.clone();
                    if matches!(stmt, Statement::Loop { .. }) {
                        entry.retain(|v, _| !stored.contains(v));
                    }
                    for_each_child(stmt, |b| prune_block(b, eval, &mut entry.clone(), removed));
                    known.retain(|v, _| !stored.contains(v));
                }
                _ => {}
            },
        }
        // What follows a statement that always leaves the block never runs (a pruned branch that returns, say).
        if terminates(stmt) {
            end = index + 1;
            break;
        }
    }
    if end < block.len() {
        defined_in(&block[end..], removed);
        block.cull(end..);
    }
}

/// Whether a statement always leaves the block it is in (returns, breaks, continues or discards on every path).
fn terminates(stmt: &Statement) -> bool {
    match stmt {
        Statement::Return { .. } | Statement::Kill | Statement::Break | Statement::Continue => true,
        Statement::Block(b) => b.last().is_some_and(terminates),
        Statement::If { accept, reject, .. } => {
            accept.last().is_some_and(terminates) && reject.last().is_some_and(terminates)
        }
        _ => false,
    }
}

/// The simple locals a block stores to, anywhere inside it.
fn stored_in(block: &Block, locals: &SimpleLocals, out: &mut HashSet<Handle<naga::LocalVariable>>) {
    for stmt in block.iter() {
        match stmt {
            Statement::Store { pointer, .. } => out.extend(locals.variable(*pointer)),
            Statement::Block(b) => stored_in(b, locals, out),
            Statement::If { accept, reject, .. } => {
                stored_in(accept, locals, out);
                stored_in(reject, locals, out);
            }
            Statement::Switch { cases, .. } => cases.iter().for_each(|c| stored_in(&c.body, locals, out)),
            Statement::Loop { body, continuing, .. } => {
                stored_in(body, locals, out);
                stored_in(continuing, locals, out);
            }
            _ => {}
        }
    }
}

/// The body a switch on the constant `value` runs (with the cases it falls through to), taken out of `cases`; None
/// where that body has a `break` of the switch itself, which a plain block could not express.
fn taken_case(value: Literal, cases: &mut [naga::SwitchCase], removed: &mut Vec<Handle<Expression>>) -> Option<Block> {
    let matches = |c: &naga::SwitchCase| match (c.value, value) {
        (SwitchValue::U32(a), Literal::U32(b)) => a == b,
        (SwitchValue::I32(a), Literal::I32(b)) => a == b,
        _ => false,
    };
    let first =
        cases.iter().position(matches).or_else(|| cases.iter().position(|c| c.value == SwitchValue::Default))?;
    let last = first + cases[first..].iter().position(|c| !c.fall_through)?;
    if cases[first..=last].iter().any(|c| breaks_out(&c.body)) {
        return None;
    }
    let mut taken = Block::new();
    for (i, c) in cases.iter_mut().enumerate() {
        if (first..=last).contains(&i) {
            taken.append(&mut c.body);
        } else {
            defined_in(&c.body, removed);
        }
    }
    Some(taken)
}

/// Whether a block has a `break` that leaves the construct around it (not one inside a nested loop or switch).
fn breaks_out(block: &Block) -> bool {
    block.iter().any(|s| match s {
        Statement::Break => true,
        Statement::Block(b) => breaks_out(b),
        Statement::If { accept, reject, .. } => breaks_out(accept) || breaks_out(reject),
        _ => false,
    })
}

/// Every expression a block's statements define (emit, or produce as a call's or an atomic's result).
fn defined_in(block: &[Statement], out: &mut Vec<Handle<Expression>>) {
    for stmt in block.iter() {
        match stmt {
            Statement::Emit(range) => out.extend(range.clone()),
            Statement::Call { result: Some(r), .. }
            | Statement::Atomic { result: Some(r), .. }
            | Statement::WorkGroupUniformLoad { result: r, .. }
            | Statement::SubgroupBallot { result: r, .. }
            | Statement::SubgroupGather { result: r, .. }
            | Statement::SubgroupCollectiveOperation { result: r, .. } => out.push(*r),
            Statement::If { accept, reject, .. } => {
                defined_in(accept, out);
                defined_in(reject, out);
            }
            Statement::Switch { cases, .. } => cases.iter().for_each(|c| defined_in(&c.body, out)),
            Statement::Block(b) => defined_in(b, out),
            Statement::Loop { body, continuing, .. } => {
                defined_in(body, out);
                defined_in(continuing, out);
            }
            _ => {}
        }
    }
}
