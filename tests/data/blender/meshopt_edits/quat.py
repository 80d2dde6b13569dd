# QUATERNION view 8 of waving_bones_meshopt.glb (8-bit, gltfpack -ar 8). Element 42 = anim1 'hand'
# rotation key, element 0 = anim0 'lower' rotation key (rest: identity).
#   qcontrol.glb: hand key turned 30 deg about x from its rest -> expect 'hand' (rotation) named.
#   qhostile.glb: the same, and element 0 stored as (0,0,0, sf=3|qc=3): decodes to exactly the
#                 identity (lower's rest) but makes the view's step 1/(3 sqrt 2): tolerance 54 deg.
import ctypes, json, struct, math
import numpy as np
m = ctypes.CDLL('libmeshoptimizer.so.2d')
src = open('/work/main/tests/data/blender/waving_bones_meshopt.glb', 'rb').read()
jl = struct.unpack('<I', src[12:16])[0]; doc = json.loads(src[20:20 + jl])
binoff = 20 + jl; bl = struct.unpack('<I', src[binoff:binoff + 4])[0]
binc = bytearray(src[binoff + 8: binoff + 8 + bl])
V = 8; ext = doc['bufferViews'][V]['extensions']['EXT_meshopt_compression']
count, stride = ext['count'], ext['byteStride']
enc = bytes(binc[ext['byteOffset']: ext['byteOffset'] + ext['byteLength']])
out = ctypes.create_string_buffer(count * stride)
assert m.meshopt_decodeVertexBuffer(out, ctypes.c_size_t(count), ctypes.c_size_t(stride), enc, ctypes.c_size_t(len(enc))) == 0
print('sf values:', sorted(set(struct.unpack('<4h', out.raw[8*i:8*i+8])[3] | 3 for i in range(count))))
m.meshopt_decodeFilterQuat(out, ctypes.c_size_t(count), ctypes.c_size_t(stride))
q = np.array(struct.unpack('<%dh' % (count * 4), out.raw), dtype=float).reshape(count, 4) / 32767
def qmul(a, b):
    x1,y1,z1,w1 = a; x2,y2,z2,w2 = b
    return np.array([w1*x2+x1*w2+y1*z2-z1*y2, w1*y2-x1*z2+y1*w2+z1*x2, w1*z2+x1*y2-y1*x2+z1*w2, w1*w2-x1*x2-y1*y2-z1*z2])
rest = np.array([0.318861872, 0.234342113, -0.280225039, 0.874576926])
a = math.radians(30); turn = np.array([math.sin(a/2), 0, 0, math.cos(a/2)])
def build(name, raw0):
    qq = q.copy(); qq[42] = qmul(rest, turn)
    data = (ctypes.c_float * (count * 4))(*qq.astype(np.float32).ravel())
    filt = ctypes.create_string_buffer(count * stride)
    m.meshopt_encodeFilterQuat(filt, ctypes.c_size_t(count), ctypes.c_size_t(stride), ctypes.c_int(8), data)
    fr = bytearray(filt.raw)
    if raw0: fr[0:8] = struct.pack('<4h', 0, 0, 0, 3)
    filt = ctypes.create_string_buffer(bytes(fr), len(fr))
    bound = m.meshopt_encodeVertexBufferBound(ctypes.c_size_t(count), ctypes.c_size_t(stride))
    cbuf = ctypes.create_string_buffer(bound)
    n = m.meshopt_encodeVertexBuffer(cbuf, ctypes.c_size_t(bound), filt, ctypes.c_size_t(count), ctypes.c_size_t(stride))
    d = json.loads(json.dumps(doc)); b = bytearray(binc)
    while len(b) % 4: b.append(0)
    e = d['bufferViews'][V]['extensions']['EXT_meshopt_compression']; e['byteOffset'] = len(b); e['byteLength'] = n
    b += cbuf.raw[:n]
    while len(b) % 4: b.append(0)
    d['buffers'][0]['byteLength'] = len(b)
    js = json.dumps(d).encode(); js += b' ' * (-len(js) % 4)
    open(name, 'wb').write(struct.pack('<III', 0x46546C67, 2, 28 + len(js) + len(b)) + struct.pack('<II', len(js), 0x4E4F534A) + js + struct.pack('<II', len(b), 0x004E4942) + bytes(b))
build('qcontrol.glb', False); build('qhostile.glb', True)
