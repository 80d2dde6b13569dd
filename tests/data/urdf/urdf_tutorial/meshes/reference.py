#!/usr/bin/env python3
"""Independent COLLADA reference reader for the rdtf import tests (no assimp, no Blender).

Reads COLLADA 1.4 files with xml.etree and numpy (float64) and applies the ROS (RViz/MoveIt)
convention: every node transform (<matrix>, <translate>, <rotate> axis+degrees, <scale>; the
node's local matrix is the product of its elements in document order, children under their
parents), <unit meter> applied, <up_axis> IGNORED. Only POSITION is read. <triangles>,
<polylist> and <polygons> (fan-triangulated) of every <instance_geometry> reachable from the
<scene>'s visual scene (following <instance_node> too) are collected.

Per file it reports: triangle count, axis-aligned min/max of all triangle corners (metres),
whether the surface is closed (after welding exactly equal transformed positions, every
directed edge is matched by its reverse, counted as a multiset), and per material
(instance_material symbol -> material id/name) the triangle count and the diffuse colour if it
is a <color> (or that it is a <texture>).

Usage: reference.py FILE.dae [...] [--json OUT.json] [--scale sx sy sz]
"""
import json
import math
import sys
import xml.etree.ElementTree as ET
from collections import Counter, OrderedDict

import numpy as np


def local(tag):
    return tag.rsplit('}', 1)[-1]


def floats(text):
    return [float(t) for t in (text or '').split()]


def ints(text):
    return [int(t) for t in (text or '').split()]


class Doc:
    def __init__(self, path):
        self.root = ET.parse(path).getroot()
        self.ns = self.root.tag[:-len('COLLADA')]  # '{...}' or ''
        self.ids = {}
        for el in self.root.iter():
            i = el.get('id')
            if i is not None:
                self.ids[i] = el

    def q(self, name):
        return self.ns + name

    def ref(self, url):
        if not url or not url.startswith('#'):
            raise ValueError('external or empty reference not supported: %r' % url)
        return self.ids[url[1:]]

    def unit(self):
        asset = self.root.find(self.q('asset'))
        if asset is not None:
            u = asset.find(self.q('unit'))
            if u is not None and u.get('meter') is not None:
                return float(u.get('meter'))
        return 1.0

    def up_axis(self):
        asset = self.root.find(self.q('asset'))
        if asset is not None:
            u = asset.find(self.q('up_axis'))
            if u is not None:
                return u.text.strip()
        return 'Y_UP'

    # --- sources -----------------------------------------------------------------------
    def source_array(self, url):
        """Returns an (count, stride-params) float64 array of a <source>'s accessor."""
        src = self.ref(url)
        if local(src.tag) == 'vertices':
            raise ValueError('expected a source, got vertices')
        acc = src.find(self.q('technique_common')).find(self.q('accessor'))
        arr_el = self.ref(acc.get('source')) if acc.get('source', '').startswith('#') else \
            src.find(self.q('float_array'))
        data = np.array(floats(arr_el.text), dtype=np.float64)
        count = int(acc.get('count'))
        stride = int(acc.get('stride', '1'))
        offset = int(acc.get('offset', '0'))
        params = acc.findall(self.q('param'))
        # Only named params are read, at their position within the stride.
        cols = [k for k, p in enumerate(params) if p.get('name')]
        out = np.empty((count, len(cols)))
        for j, c in enumerate(cols):
            out[:, j] = data[offset + c: offset + c + stride * count: stride][:count]
        return out

    def positions_of_vertices(self, vertices_el):
        for inp in vertices_el.findall(self.q('input')):
            if inp.get('semantic') == 'POSITION':
                return self.source_array(inp.get('source'))
        raise ValueError('vertices without POSITION')

    # --- primitives --------------------------------------------------------------------
    def primitive_triangles(self, mesh, prim):
        """Returns (positions (N,3), triangles (T,3) indices into positions)."""
        kind = local(prim.tag)
        inputs = prim.findall(self.q('input'))
        max_off = max(int(i.get('offset', '0')) for i in inputs)
        stride = max_off + 1
        pos = None
        pos_off = None
        for inp in inputs:
            sem = inp.get('semantic')
            if sem == 'VERTEX':
                pos = self.positions_of_vertices(self.ref(inp.get('source')))
                pos_off = int(inp.get('offset', '0'))
        if pos is None:
            for inp in inputs:
                if inp.get('semantic') == 'POSITION':
                    pos = self.source_array(inp.get('source'))
                    pos_off = int(inp.get('offset', '0'))
        if pos is None:
            raise ValueError('primitive without VERTEX/POSITION')

        polys = []  # list of lists of position indices
        if kind == 'triangles':
            idx = ints(prim.find(self.q('p')).text)
            corners = idx[pos_off::stride]
            n = int(prim.get('count'))
            corners = corners[:3 * n]
            polys = [corners[k:k + 3] for k in range(0, len(corners), 3)]
        elif kind == 'polylist':
            idx = ints(prim.find(self.q('p')).text)
            vc = ints(prim.find(self.q('vcount')).text)
            corners = idx[pos_off::stride]
            at = 0
            for c in vc:
                polys.append(corners[at:at + c])
                at += c
        elif kind == 'polygons':
            for p in prim.findall(self.q('p')):
                idx = ints(p.text)
                polys.append(idx[pos_off::stride])
            for ph in prim.findall(self.q('ph')):  # polygon with holes: outer <p> only
                p = ph.find(self.q('p'))
                polys.append(ints(p.text)[pos_off::stride])
        else:
            raise ValueError('unsupported primitive ' + kind)

        tris = []
        for poly in polys:
            for k in range(1, len(poly) - 1):  # fan
                tris.append((poly[0], poly[k], poly[k + 1]))
        return pos, np.array(tris, dtype=np.int64).reshape(-1, 3)

    # --- materials ---------------------------------------------------------------------
    def material_info(self, material_url):
        if material_url is None:
            return None, {'diffuse': None}
        mat = self.ref(material_url)
        name = mat.get('name') or mat.get('id')
        info = {'material': name}
        ie = mat.find(self.q('instance_effect'))
        diffuse = None
        if ie is not None:
            eff = self.ref(ie.get('url'))
            for tech in eff.iter(self.q('technique')):
                for shader in tech:
                    if local(shader.tag) in ('lambert', 'phong', 'blinn', 'constant'):
                        d = shader.find(self.q('diffuse'))
                        if d is None:
                            continue
                        c = d.find(self.q('color'))
                        t = d.find(self.q('texture'))
                        if c is not None:
                            diffuse = {'color': floats(c.text)}
                        elif t is not None:
                            tex = {'texture': t.get('texture')}
                            img = self.texture_image(eff, t.get('texture'))
                            if img:
                                tex['image'] = img
                            diffuse = tex
                        break
                if diffuse is not None:
                    break
        info['diffuse'] = diffuse
        return name, info

    def texture_image(self, effect, sampler_sid):
        """Follows sampler2D -> surface -> image init_from (COLLADA 1.4)."""
        params = {np_.get('sid'): np_ for np_ in effect.iter(self.q('newparam'))}
        s = params.get(sampler_sid)
        try:
            if s is not None:
                surf_sid = s.find(self.q('sampler2D')).find(self.q('source')).text.strip()
                surf = params[surf_sid]
                img_id = surf.find(self.q('surface')).find(self.q('init_from')).text.strip()
            else:
                img_id = sampler_sid
            img = self.ids[img_id]
            return img.find(self.q('init_from')).text.strip()
        except (AttributeError, KeyError):
            return None


def rot(axis, deg):
    a = np.array(axis, dtype=np.float64)
    n = np.linalg.norm(a)
    m = np.eye(4)
    if n == 0.0:
        return m
    x, y, z = a / n
    t = math.radians(deg)
    c, s = math.cos(t), math.sin(t)
    C = 1.0 - c
    m[:3, :3] = [[c + x * x * C, x * y * C - z * s, x * z * C + y * s],
                 [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
                 [z * x * C - y * s, z * y * C + x * s, c + z * z * C]]
    return m


def node_local(doc, node):
    m = np.eye(4)
    for el in node:
        k = local(el.tag)
        v = floats(el.text)
        if k == 'matrix':
            e = np.array(v, dtype=np.float64).reshape(4, 4)  # row-major in the file
        elif k == 'translate':
            e = np.eye(4)
            e[:3, 3] = v
        elif k == 'rotate':
            e = rot(v[:3], v[3])
        elif k == 'scale':
            e = np.diag([v[0], v[1], v[2], 1.0])
        elif k in ('lookat', 'skew'):
            raise ValueError('unsupported transform element ' + k)
        else:
            continue
        m = m @ e
    return m


def collect(doc, node, parent, out, depth=0):
    if depth > 64:
        raise ValueError('node nesting too deep (cycle?)')
    world = parent @ node_local(doc, node)
    for el in node:
        k = local(el.tag)
        if k == 'instance_geometry':
            binds = {}
            bm = el.find(doc.q('bind_material'))
            if bm is not None:
                for im in bm.iter(doc.q('instance_material')):
                    binds[im.get('symbol')] = im.get('target')
            out.append((world, doc.ref(el.get('url')), binds))
        elif k == 'instance_node':
            collect(doc, doc.ref(el.get('url')), world, out, depth + 1)
        elif k == 'node':
            collect(doc, el, world, out, depth + 1)


def analyse(path, mesh_scale=(1.0, 1.0, 1.0)):
    doc = Doc(path)
    unit = doc.unit()
    root = np.diag([unit * mesh_scale[0], unit * mesh_scale[1], unit * mesh_scale[2], 1.0])
    scene = doc.root.find(doc.q('scene'))
    vs = doc.ref(scene.find(doc.q('instance_visual_scene')).get('url'))
    insts = []
    for n in vs.findall(doc.q('node')):
        collect(doc, n, root, insts)

    all_pts = []      # transformed corner positions, one (T,3,3) block per primitive
    materials = OrderedDict()
    for world, geom, binds in insts:
        mesh = geom.find(doc.q('mesh'))
        if mesh is None:
            continue
        for prim in mesh:
            kind = local(prim.tag)
            if kind not in ('triangles', 'polylist', 'polygons'):
                if kind in ('lines', 'linestrips', 'trifans', 'tristrips'):
                    print('  note: %s primitive ignored' % kind, file=sys.stderr)
                continue
            pos, tris = doc.primitive_triangles(mesh, prim)
            p4 = np.hstack([pos, np.ones((len(pos), 1))])
            tp = (world @ p4.T).T[:, :3]
            corners = tp[tris]  # (T,3,3)
            all_pts.append(corners)
            sym = prim.get('material')
            name, info = doc.material_info(binds.get(sym)) if sym in binds else (None, {'diffuse': None})
            key = '%s/%s' % (sym, name)
            entry = materials.setdefault(key, {'symbol': sym, 'material': name, 'triangles': 0,
                                               'diffuse': info['diffuse']})
            entry['triangles'] += len(tris)

    corners = np.concatenate(all_pts) if all_pts else np.zeros((0, 3, 3))
    flat = corners.reshape(-1, 3)
    # Weld exactly equal positions, then check every directed edge has its reverse.
    weld = {}
    ids = np.array([weld.setdefault(tuple(p), len(weld)) for p in flat.tolist()]).reshape(-1, 3)
    edges = Counter()
    degenerate = 0
    for a, b, c in ids.tolist():
        if a == b or b == c or c == a:
            degenerate += 1
        edges[(a, b)] += 1
        edges[(b, c)] += 1
        edges[(c, a)] += 1
    unmatched = sum(abs(n - edges.get((b, a), 0)) for (a, b), n in edges.items())
    return OrderedDict([
        ('triangles', int(len(corners))),
        ('min', flat.min(axis=0).tolist() if len(flat) else None),
        ('max', flat.max(axis=0).tolist() if len(flat) else None),
        ('closed', unmatched == 0),
        ('materials', OrderedDict((k, {kk: vv for kk, vv in v.items() if kk not in ('symbol', 'material')})
                                  for k, v in materials.items())),
        ('_detail', {'up_axis_ignored': doc.up_axis(), 'unit': unit,
                     'welded_vertices': len(weld), 'unmatched_directed_edges': unmatched,
                     'degenerate_triangles': degenerate}),
    ])


def main(argv):
    out_json = None
    scale = (1.0, 1.0, 1.0)
    files = []
    i = 0
    while i < len(argv):
        if argv[i] == '--json':
            out_json = argv[i + 1]
            i += 2
        elif argv[i] == '--scale':
            scale = tuple(float(x) for x in argv[i + 1:i + 4])
            i += 4
        else:
            files.append(argv[i])
            i += 1
    results = OrderedDict()
    for f in files:
        r = analyse(f, scale)
        name = f.rsplit('/', 1)[-1]
        results[name] = r
        print('%s: %d triangles, closed=%s' % (name, r['triangles'], r['closed']))
        print('  min %s' % ['%.9g' % x for x in r['min']])
        print('  max %s' % ['%.9g' % x for x in r['max']])
        for k, v in r['materials'].items():
            print('  material %s: %d triangles, diffuse %s' % (k, v['triangles'], v['diffuse']))
        print('  detail %s' % r['_detail'])
    if out_json:
        clean = OrderedDict((k, OrderedDict((kk, vv) for kk, vv in v.items() if not kk.startswith('_')))
                            for k, v in results.items())
        with open(out_json, 'w') as fh:
            json.dump(clean, fh, indent=2)
            fh.write('\n')


if __name__ == '__main__':
    main(sys.argv[1:])
