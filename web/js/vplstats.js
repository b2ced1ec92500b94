// vplstats.js -- what a `stats` message's VPL counts mean, in one place, so the stats panel, the VPL
// chart and the domain caption say the same thing: whether the frame had a VPL step at all (pt has
// no VPLs; a refinement pass keeps its frame's set unchanged), whether its set is new (the first
// frame, a regeneration, ir every frame: nothing was kept, so "valid" means nothing) or was updated
// incrementally (iir: kept, inserted, deleted, invalidated).

// stats -> {kind: 'none'|'refined'|'new'|'updated', count, nulls, kept, inserted, deleted,
// invalidated}; kept is null unless the set was updated incrementally.
export function vplStep(stats) {
    const x = (stats && stats.vpl) || {};
    const count = x.count || 0;
    const base = { count, nulls: x.null || 0, kept: null, inserted: 0, deleted: 0, invalidated: 0 };
    if (!count) return { ...base, kind: 'none' };
    if (stats.pass > 0) return { ...base, kind: 'refined' };
    const fresh = x.regenerated > 0 || (!x.valid && x.inserted >= count && !x.deleted);
    return {
        ...base,
        kind: fresh ? 'new' : 'updated',
        kept: fresh ? null : x.valid,
        inserted: x.inserted || 0,
        deleted: x.deleted || 0,
        invalidated: x.invalidated || 0,
    };
}

// Two short texts for the stats panel: the set and what changed in it.
export function describeStep(step, method, pass) {
    if (step.kind === 'none') return { set: `none (${method || 'method'} has no VPLs)`, change: '–' };
    const nulls = step.nulls ? ` · ${step.nulls} null` : '';
    const set = `${step.count}${nulls}`;
    if (step.kind === 'refined') return { set, change: `unchanged (pass ${pass})` };
    if (step.kind === 'new') return { set, change: `new set (+${step.inserted})` };
    return { set, change: `kept ${step.kept} · +${step.inserted} −${step.deleted} ✗${step.invalidated}` };
}
