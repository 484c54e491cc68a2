"""Structure-aware mutants of OpenVDB and NanoVDB node tables, for tools/mutants.py.

Byte-wise mutation of a sparse file rarely keeps it parseable past the first node: what breaks a reader there is a
file whose *structure* lies while every byte is well formed. These mutants are made at the level of the tree:

  - OpenVDB (`openvdb(rng)`): a tree drawn at random — leaves in clusters or far apart (up to the edges of int32
    index space), constant tiles at every level (4096³ root tiles, 128³ and 8³ node tiles), values that are
    NaN, infinite, huge or denormal, extreme backgrounds and maps — written by a writer that can lie: child
    masks with bits set for nodes never written or cleared for nodes that are, root counts off by one or
    by 2³², a root child twice, unaligned origins, value-coding bytes and compression flags that do not match the
    data, grid offsets past the end or before the start, the wrong tree type;
  - NanoVDB (`nanovdb(seed, rng)`): a valid file patched field by field — root keys repeated or far, child
    offsets onto a shared node (a DAG), onto the wrong level or between nodes, child masks filled, node tables
    of tiles, tree counts and offsets off, maps degenerate, leaf values and origins extreme.

Either may then take a few byte-wise mutations as well (one in eight).
"""
import struct

EXTREME_F32 = [float("nan"), float("inf"), float("-inf"), 3.4e38, -3.4e38, 1e-45, -0.0, 0.0, 1e30, -1.0, 1e9]
EXTREME_I32 = [0, 8, -8, 4096, -4096, 2**24, -(2**24), 2**30, -(2**30), 2**31 - 8, -(2**31), 2**31 - 4096]


def _f32(rng, normal=1.0):
    return rng.choice(EXTREME_F32) if rng.random() < 0.2 else rng.random() * normal


def _u32(v):
    return struct.pack("<I", v % (1 << 32))


def _i32(v):
    return struct.pack("<i", ((v + 2**31) % 2**32) - 2**31)


def _str(s):
    b = s.encode()
    return _u32(len(b)) + b


# ---- OpenVDB: a random tree, and a writer that can lie


def _tree(rng):
    """Leaves, node tiles and root tiles of one grid: {leaves: {origin: (mask, values)}, t8, t128, t4096}."""
    leaves = {}
    shape = rng.randrange(5)
    if shape == 0:  # a cluster
        base = [rng.choice([0, 64, -4096, 1 << 20]) for _ in range(3)]
        for _ in range(rng.randint(1, 40)):
            o = tuple(base[a] + 8 * rng.randrange(-8, 8) for a in range(3))
            leaves[o] = None
    elif shape == 1:  # far apart: thousands of voxels, or to the edges of index space
        for _ in range(rng.randint(2, 4)):
            far = (lambda: rng.choice(EXTREME_I32)) if rng.random() < 0.25 else (lambda: rng.randrange(-(1 << 13), 1 << 13))
            leaves[tuple((far() // 8) * 8 for _ in range(3))] = None
    elif shape == 2:  # one leaf
        leaves[(0, 0, 0)] = None
    elif shape == 3:  # a line of leaves along one axis
        a = rng.randrange(3)
        step = rng.choice([8, 128, 4096, 1 << 16])
        for k in range(rng.randint(2, 30)):
            o = [0, 0, 0]
            o[a] = k * step
            leaves[tuple(o)] = None
    # shape 4: no leaves, tiles only
    for o in list(leaves):
        full = rng.random() < 0.5
        mask = [(1 << 64) - 1] * 8 if full else [rng.getrandbits(64) for _ in range(8)]
        scale = rng.choice([1.0, 1500.0, 1e-3])
        # (One leaf in eight holds extreme values — NaN, infinities, denormals — among ordinary ones.)
        extreme = rng.random() < 0.125
        vals = [_f32(rng, scale) if extreme else rng.random() * scale for _ in range(512)]
        leaves[o] = (mask, vals)
    t8 = [(tuple(8 * rng.randrange(-4, 4) + 256 for _ in range(3)), _f32(rng)) for _ in range(rng.choice([0, 0, 1, 5]))]
    t128 = [(tuple(128 * rng.randrange(-4, 4) for _ in range(3)), _f32(rng)) for _ in range(rng.choice([0, 0, 1, 8, 64]))]
    t4096 = [(tuple(4096 * rng.randrange(-3, 3) for _ in range(3)), _f32(rng), rng.random() < 0.7)
             for _ in range(rng.choice([0, 0, 0, 0, 0, 0, 1, 3]))]
    # A node tile and a leaf in the same place is not a tree: keep the leaves.
    t8 = [t for t in t8 if t[0] not in leaves]
    return {"leaves": leaves, "t8": t8, "t128": t128, "t4096": t4096}


def _key5(o):
    return tuple(v >> 12 for v in o)


def _index4(o):
    return ((o[0] >> 7) & 31) << 10 | ((o[1] >> 7) & 31) << 5 | ((o[2] >> 7) & 31)


def _index_leaf(o):
    return ((o[0] >> 3) & 15) << 8 | ((o[1] >> 3) & 15) << 4 | ((o[2] >> 3) & 15)


def _mask_bytes(bits, words):
    m = [0] * words
    for k in bits:
        m[k // 64] |= 1 << (k % 64)
    return b"".join(struct.pack("<Q", w) for w in m)


def _values(rng, n, dense, lie):
    """A node's values: value-coding byte 6 (all stored) unless the writer lies about it."""
    meta = 6
    if lie and rng.random() < 0.1:
        meta = rng.randrange(8)
    out = bytes([meta])
    vals = [0.0] * n
    for k, v in dense.items():
        vals[k] = v
    return out + struct.pack(f"<{n}f", *vals)


def _grid(rng, tree, lies):
    """The bytes of one grid after its descriptor's offsets: (head, topology, blocks) with the lies applied."""
    leaves = sorted(tree["leaves"].items(), key=lambda kv: (_key5(kv[0]), _index4(kv[0]), _index_leaf(kv[0])))
    roots = sorted({_key5(o) for o, _ in leaves} | {_key5(t[0]) for t in tree["t8"] + tree["t128"]})
    if "dup_root" in lies and roots:
        roots.append(roots[rng.randrange(len(roots))])
    topo = b""
    bg = rng.choice(EXTREME_F32) if "background" in lies else 0.0
    topo += struct.pack("<f", bg)
    ntiles, nchildren = len(tree["t4096"]), len(roots)
    if "counts" in lies:
        d = rng.choice([1, -1, 2**32 - 1, 2**31, 1000])
        if rng.random() < 0.5:
            ntiles += d
        else:
            nchildren += d
    topo += _u32(ntiles) + _u32(nchildren)
    for o, v, active in tree["t4096"]:
        topo += b"".join(_i32(c) for c in o) + struct.pack("<f", v) + bytes([1 if active else 0])
    order = []  # leaves in the order the topology names them
    for r in roots:
        origin = [c << 12 for c in r]
        if "unaligned" in lies and rng.random() < 0.3:
            origin = [c + rng.choice([1, 7, 100]) for c in origin]
        topo += b"".join(_i32(c) for c in origin)
        in5 = [(o, lv) for o, lv in leaves if _key5(o) == r]
        child5 = {_index4(o) for o, _ in in5} | {_index4(t[0]) for t in tree["t8"] if _key5(t[0]) == r}
        if "children" in lies and rng.random() < 0.3:
            if rng.random() < 0.5:
                child5 |= {rng.randrange(32768) for _ in range(rng.choice([1, 2, 512]))}
            elif child5:
                child5.discard(next(iter(child5)))
        active5 = {_index4(t[0]): t[1] for t in tree["t128"] if _key5(t[0]) == r}
        topo += _mask_bytes(child5, 512) + _mask_bytes(active5.keys(), 512)
        topo += _values(rng, 32768, active5, "coding" in lies)
        for k4 in sorted(child5):
            in4 = [(o, lv) for o, lv in in5 if _index4(o) == k4]
            child4 = {_index_leaf(o) for o, _ in in4}
            if "children" in lies and rng.random() < 0.2:
                child4 |= {rng.randrange(4096) for _ in range(rng.choice([1, 4096]))}
            active4 = {_index_leaf(t[0]): t[1] for t in tree["t8"] if _key5(t[0]) == r and _index4(t[0]) == k4}
            topo += _mask_bytes(child4, 64) + _mask_bytes(active4.keys(), 64)
            topo += _values(rng, 4096, active4, "coding" in lies)
            for o, (mask, _) in in4:
                topo += b"".join(struct.pack("<Q", w) for w in mask)
                order.append(o)
    blocks = b""
    for o in order:
        mask, vals = tree["leaves"][o]
        blocks += b"".join(struct.pack("<Q", w) for w in mask)
        blocks += bytes([rng.randrange(8) if "coding" in lies and rng.random() < 0.1 else 6])
        blocks += struct.pack("<512f", *vals)
    if "blocks" in lies and blocks:
        blocks = blocks[: rng.randrange(len(blocks))] if rng.random() < 0.5 else blocks + blocks[:2048]
    return topo, blocks


def _map(rng, lie):
    voxel = rng.choice([0.01, 1.0, 0.1])
    kind = rng.choice(["ScaleTranslateMap", "UniformScaleTranslateMap", "ScaleMap", "TranslationMap", "AffineMap"]) \
        if lie else "ScaleTranslateMap"
    bad = [0.0, -0.01, float("nan"), float("inf"), 1e-30, 1e30, 1e300]
    v = [rng.choice(bad) if lie and rng.random() < 0.3 else voxel for _ in range(3)]
    t = [rng.choice([1e300, -1e300, float("nan")]) if lie and rng.random() < 0.2 else 0.0 for _ in range(3)]
    if kind in ("ScaleTranslateMap", "UniformScaleTranslateMap"):
        vecs = [t, v, v, [1 / x if x else 0 for x in v], [1 / (x * x) if x else 0 for x in v], [0.5 / x if x else 0 for x in v]]
    elif kind == "ScaleMap":
        vecs = [v, v, [1 / x if x else 0 for x in v], [1 / (x * x) if x else 0 for x in v], [0.5 / x if x else 0 for x in v]]
    elif kind == "TranslationMap":
        vecs = [t]
    else:
        m = [v[0], 0, 0, 0, 0, v[1], 0, 0, 0, 0, v[2], 0, t[0], t[1], t[2], 1]
        if rng.random() < 0.3:
            m[rng.randrange(16)] = rng.choice([0.5, -1.0, float("nan")])
        return _str(kind) + struct.pack("<16d", *m)
    return _str(kind) + b"".join(struct.pack("<3d", *x) for x in vecs)


def openvdb(rng):
    """An OpenVDB file of one or two float grids (density, temperature) whose tree is drawn at random and whose
    writer lies about its structure in one or two ways (or, about one time in three, not at all)."""
    every = ["dup_root", "counts", "unaligned", "children", "coding", "blocks", "background", "map", "offsets",
             "compression", "type", "grids"]
    lies = set() if rng.random() < 0.35 else set(rng.sample(every, rng.randint(1, 2)))
    names = ["density", "temperature"][: rng.randint(1, 2)]
    shared = _tree(rng)
    # (Channels share one lattice: one map for both grids, unless the map is the lie.)
    one_map = _map(rng, False)
    out = struct.pack("<q", 0x56444220) + _u32(224) + _u32(12) + _u32(0) + b"\x01"
    out += b"00000000-0000-0000-0000-000000000000" + _u32(0)
    ngrids = len(names) + (rng.choice([1, -1, 1000]) if "grids" in lies else 0)
    out += _i32(ngrids)
    for name in names:
        tree = shared if rng.random() < 0.8 else _tree(rng)
        ttype = rng.choice(["Tree_vec3s_5_4_3", "Tree_double_5_4_3", "Tree_float_5_4_3_HalfFloat"]) \
            if "type" in lies else "Tree_float_5_4_3"
        out += _str(name) + _str(ttype) + _str("")
        offsets_at = len(out)
        out += b"\0" * 24
        grid_pos = len(out)
        comp = rng.randrange(8) if "compression" in lies else 0
        head = _u32(comp) + _u32(0) + (_map(rng, True) if "map" in lies else one_map) + _i32(1)
        topo, blocks = _grid(rng, tree, lies)
        out += head + topo
        block_pos = len(out)
        out += blocks
        end_pos = len(out)
        offs = [grid_pos, block_pos, end_pos]
        if "offsets" in lies:
            k = rng.randrange(3)
            offs[k] = rng.choice([0, -1, len(out) + 8, 2**62, offs[k] + 1, offs[k] - 13])
        out = out[:offsets_at] + struct.pack("<3q", *offs) + out[offsets_at + 24:]
    return out


# ---- NanoVDB: a valid file patched field by field

GRID, TREE = 672, 672
UPPER_STRIDE, LOWER_STRIDE, LEAF_STRIDE = 8256 + 8 * 32768, 1088 + 8 * 4096, 96 + 2048


def _grids(b):
    """(start, tree offsets, counts) of each uncompressed grid buffer in a NanoVDB file."""
    out = []
    i = 0
    while True:
        i = b.find(b"NanoVDB", i + 1)
        if i < 0 or i + GRID + 44 > len(b):
            return out
        off = struct.unpack_from("<4Q", b, i + TREE)
        cnt = struct.unpack_from("<3I", b, i + TREE + 32)
        if all(o < len(b) for o in off):
            out.append((i, off, cnt))


def nanovdb(seed, rng):
    """`seed` (a valid uncompressed NanoVDB file) with one to four structural fields patched."""
    b = bytearray(seed)
    grids = _grids(b)
    if not grids:
        return bytes(b)
    for _ in range(rng.randint(1, 4)):
        g, off, cnt = rng.choice(grids)
        tree = g + TREE
        root = tree + off[3]
        upper = lambda k: tree + off[2] + k * UPPER_STRIDE  # noqa: E731
        lower = lambda k: tree + off[1] + k * LOWER_STRIDE  # noqa: E731
        leaf = lambda k: tree + off[0] + k * LEAF_STRIDE  # noqa: E731
        table = struct.unpack_from("<I", b, root + 24)[0]
        op = rng.randrange(16)
        try:
            if op == 0:  # root: a second entry repeating the first's key, or far keys
                if rng.random() < 0.5:
                    struct.pack_into("<I", b, root + 24, table + 1)
                    b[root + 64 + 32 * table: root + 64 + 32 * table + 32] = b[root + 64: root + 96]
                else:
                    k = sum(rng.getrandbits(21) << s for s in (0, 21, 42))
                    struct.pack_into("<Q", b, root + 64 + 32 * rng.randrange(max(table, 1)), k)
            elif op == 1:  # root: the table size huge or zero
                struct.pack_into("<I", b, root + 24, rng.choice([0, 2, 1 << 20, 2**32 - 1]))
            elif op == 2:  # root: a child offset between nodes, onto the wrong level, or back at the root
                struct.pack_into("<q", b, root + 72, rng.choice([0, 1, -64, off[1] - off[3], 96 + 8, 2**40]))
            elif op == 3:  # root: an active 4096³ tile (child 0) with an extreme value
                struct.pack_into("<qIf", b, root + 72, 0, 1, rng.choice(EXTREME_F32))
            elif op == 4:  # upper: every child bit set (32 768 children onto the lower nodes)
                b[upper(0) + 32 + 4096: upper(0) + 32 + 8192] = b"\xff" * 4096
            elif op == 5:  # upper: all table entries onto lower node 0 (a DAG)
                target = lower(0) - upper(0)
                for k in rng.sample(range(32768), rng.choice([2, 64, 32768])):
                    b[upper(0) + 32 + 4096 + k // 8] |= 1 << (k % 8)
                    struct.pack_into("<q", b, upper(0) + 8256 + 8 * k, target)
            elif op == 6:  # upper: active 128³ tiles everywhere (value mask full, child mask empty)
                b[upper(0) + 32: upper(0) + 32 + 4096] = b"\xff" * 4096
                b[upper(0) + 32 + 4096: upper(0) + 32 + 8192] = b"\0" * 4096
            elif op == 7:  # lower: all entries onto leaf 0 (a DAG) or between leaves
                target = leaf(0) - lower(0) + rng.choice([0, 0, 4, LEAF_STRIDE // 2])
                for k in rng.sample(range(4096), rng.choice([2, 64, 4096])):
                    b[lower(0) + 32 + 512 + k // 8] |= 1 << (k % 8)
                    struct.pack_into("<q", b, lower(0) + 1088 + 8 * k, target)
            elif op == 8:  # lower: every bit a tile, active, of an extreme value
                b[lower(0) + 32: lower(0) + 544] = b"\xff" * 512
                b[lower(0) + 544: lower(0) + 1056] = b"\0" * 512
                v = struct.pack("<f", rng.choice(EXTREME_F32)) + b"\0" * 4
                b[lower(0) + 1088: lower(0) + 1088 + 8 * 4096] = v * 4096
            elif op == 9:  # tree: counts off
                k = rng.randrange(3)
                struct.pack_into("<I", b, tree + 32 + 4 * k, rng.choice([0, cnt[k] + 1, cnt[k] * 1000, 2**32 - 1]))
            elif op == 10:  # tree: an offset off
                k = rng.randrange(4)
                struct.pack_into("<Q", b, tree + 8 * k, rng.choice([0, off[k] + 8, off[k] - 8, 2**63, len(b)]))
            elif op == 11:  # map: a degenerate voxel or rotation
                i = rng.randrange(9)
                struct.pack_into("<d", b, g + 384 + 8 * i, rng.choice([0.0, -1.0, 1e-300, 1e300, float("nan")]))
            elif op == 12:  # leaves: extreme values
                k = rng.randrange(max(cnt[0], 1))
                vals = struct.pack("<f", rng.choice(EXTREME_F32)) * 512
                b[leaf(k) + 96: leaf(k) + 96 + 2048] = vals
            elif op == 13:  # leaves: origins at the edge of index space, masks full
                k = rng.randrange(max(cnt[0], 1))
                struct.pack_into("<3i", b, leaf(k), *[rng.choice(EXTREME_I32) for _ in range(3)])
                b[leaf(k) + 16: leaf(k) + 80] = b"\xff" * 64
            elif op == 14:  # the grid's size or type
                struct.pack_into("<Q", b, g + 32, rng.choice([0, 672, len(b) * 2, 2**63]))
            else:  # the background
                struct.pack_into("<f", b, root + 28, rng.choice(EXTREME_F32))
        except (struct.error, ValueError, IndexError):
            pass
    return bytes(b)
