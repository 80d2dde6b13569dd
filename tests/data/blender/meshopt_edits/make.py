# Rewrites view 7 (EXPONENTIAL, 8-bit mantissa as gltfpack -at 8 wrote it) of the fixture
# tests/data/blender/waving_bones_meshopt.glb with libmeshoptimizer 0.18 (ctypes).
# Elements of view 7: 0-1 anim0 'lower' translation, 2 anim0 'upper', 3 anim0 'hand',
# 4 anim1 'lower', 5 anim1 'upper', 6 anim1 'hand' (rest of hand: 0 0.3 0).
#   control.glb: anim1 'hand' translation key -> (0, 0.35, 0): a 5 cm move.
#   hidden.glb : the same, and anim0 'lower' keys -> (20, 0, 0) (a 20 m move, warned on its own).
import ctypes, json, struct, sys
m = ctypes.CDLL('libmeshoptimizer.so.2d')
src = open('/work/main/tests/data/blender/waving_bones_meshopt.glb', 'rb').read()
jl = struct.unpack('<I', src[12:16])[0]
doc = json.loads(src[20:20 + jl])
binoff = 20 + jl
bl = struct.unpack('<I', src[binoff:binoff + 4])[0]
binc = bytearray(src[binoff + 8: binoff + 8 + bl])
V = 7
ext = doc['bufferViews'][V]['extensions']['EXT_meshopt_compression']
count, stride = ext['count'], ext['byteStride']
enc = bytes(binc[ext['byteOffset']: ext['byteOffset'] + ext['byteLength']])
out = ctypes.create_string_buffer(count * stride)
assert m.meshopt_decodeVertexBuffer(out, ctypes.c_size_t(count), ctypes.c_size_t(stride), enc, ctypes.c_size_t(len(enc))) == 0
raw = bytearray(out.raw)
words = struct.unpack('<%di' % (count * stride // 4), raw)
print('exponents in view 7:', sorted(set(w >> 24 for w in words)))
m.meshopt_decodeFilterExp(out, ctypes.c_size_t(count), ctypes.c_size_t(stride))
vals = list(struct.unpack('<%df' % (count * 3), out.raw))
print('decoded:', [vals[3*i:3*i+3] for i in range(count)])
def build(name, changes):
    v = vals[:]
    for i, xyz in changes.items(): v[3*i:3*i+3] = xyz
    data = (ctypes.c_float * len(v))(*v)
    filt = ctypes.create_string_buffer(count * stride)
    m.meshopt_encodeFilterExp(filt, ctypes.c_size_t(count), ctypes.c_size_t(stride), ctypes.c_int(8), data)
    bound = m.meshopt_encodeVertexBufferBound(ctypes.c_size_t(count), ctypes.c_size_t(stride))
    cbuf = ctypes.create_string_buffer(bound)
    n = m.meshopt_encodeVertexBuffer(cbuf, ctypes.c_size_t(bound), filt, ctypes.c_size_t(count), ctypes.c_size_t(stride))
    d = json.loads(json.dumps(doc)); b = bytearray(binc)
    while len(b) % 4: b.append(0)
    e = d['bufferViews'][V]['extensions']['EXT_meshopt_compression']
    e['byteOffset'] = len(b); e['byteLength'] = n
    b += cbuf.raw[:n]
    while len(b) % 4: b.append(0)
    d['buffers'][0]['byteLength'] = len(b)
    js = json.dumps(d).encode(); js += b' ' * (-len(js) % 4)
    glb = struct.pack('<III', 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(b)) + struct.pack('<II', len(js), 0x4E4F534A) + js + struct.pack('<II', len(b), 0x004E4942) + bytes(b)
    open(name, 'wb').write(glb)
build('control.glb', {6: [0, 0.35, 0]})
build('hidden.glb', {6: [0, 0.35, 0], 0: [20, 0, 0], 1: [20, 0, 0]})

# hostile.glb: as control.glb (anim1 'hand' moves 5 cm), and the two keys of anim0 'lower'
# (rest: no translation) stored as mantissa 0 with exponent +127: they decode to exactly 0, the
# rest, yet set the view's step to 2^127. nan.glb: exponent -128 (decodes to NaN).
def build_raw(name, changes, raw_words):
    v = vals[:]
    for i, xyz in changes.items(): v[3*i:3*i+3] = xyz
    data = (ctypes.c_float * len(v))(*v)
    filt = ctypes.create_string_buffer(count * stride)
    m.meshopt_encodeFilterExp(filt, ctypes.c_size_t(count), ctypes.c_size_t(stride), ctypes.c_int(8), data)
    fr = bytearray(filt.raw)
    for wi, w in raw_words.items(): fr[4*wi:4*wi+4] = struct.pack('<I', w)
    filt = ctypes.create_string_buffer(bytes(fr), len(fr))
    bound = m.meshopt_encodeVertexBufferBound(ctypes.c_size_t(count), ctypes.c_size_t(stride))
    cbuf = ctypes.create_string_buffer(bound)
    n = m.meshopt_encodeVertexBuffer(cbuf, ctypes.c_size_t(bound), filt, ctypes.c_size_t(count), ctypes.c_size_t(stride))
    d = json.loads(json.dumps(doc)); b = bytearray(binc)
    while len(b) % 4: b.append(0)
    e = d['bufferViews'][V]['extensions']['EXT_meshopt_compression']
    e['byteOffset'] = len(b); e['byteLength'] = n
    b += cbuf.raw[:n]
    while len(b) % 4: b.append(0)
    d['buffers'][0]['byteLength'] = len(b)
    js = json.dumps(d).encode(); js += b' ' * (-len(js) % 4)
    glb = struct.pack('<III', 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(b)) + struct.pack('<II', len(js), 0x4E4F534A) + js + struct.pack('<II', len(b), 0x004E4942) + bytes(b)
    open(name, 'wb').write(glb)
build_raw('hostile.glb', {6: [0, 0.35, 0]}, {w: (127 << 24) for w in range(6)})
build_raw('nan.glb', {6: [0, 0.35, 0]}, {w: (0x80 << 24) | 1 for w in range(6)})
