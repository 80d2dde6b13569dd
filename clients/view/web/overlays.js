// A model's overlays - each link's joint frame (axes), each joint's axis (an arrow), the centres
// of mass and the equivalent-inertia boxes - in four draw calls, whatever the number of links.
//
// Why not a helper object each (AxesHelper, ArrowHelper, a sphere, a box per link): each is a
// draw call and three.js's work on the main thread at every frame, and helpers made a 3-link arm
// 17 draw calls, a 23-link quadruped 114 and a 100-link model over 500 (arm3's submit is 1-2 ms a
// frame shorter without them: docs/benchmarks.md, "Overlays in four draw calls"). Here the lines'
// few vertices are placed on the CPU at each pose, in the scene frame S (the model's `root`), and
// the arrow heads and spheres are instances.
import * as THREE from 'three';

const AXIS_COLORS = [new THREE.Color(1, 0, 0), new THREE.Color(0, 1, 0), new THREE.Color(0, 0, 1)];
const AXIS_CYAN = new THREE.Color(0x00e0ff);
const RED = new THREE.Color(0xff2020);
const COM_YELLOW = new THREE.Color(0xffff00);
const TOTAL_MAGENTA = new THREE.Color(0xff00ff);
// A box's corner k is (+-a/2, +-b/2, +-c/2), the sign of each by bit 0, 1, 2 of k; its 12 edges.
const BOX_EDGES = [[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7], [0, 4], [1, 5], [2, 6], [3, 7]];
const Y = new THREE.Vector3(0, 1, 0);

// Lines coloured per vertex, with room for `vertices`; drawn up to the count last written.
function lineSegments(vertices, depthTest) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * vertices), 3).setUsage(THREE.DynamicDrawUsage));
  geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(3 * vertices), 3).setUsage(THREE.DynamicDrawUsage));
  const lines = new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ vertexColors: true, depthTest }));
  lines.matrixAutoUpdate = false;
  return lines;
}

// Writes vertex after vertex into a lineSegments' buffers; done() sets what is drawn.
class LineWriter {
  constructor(lines) {
    this.lines = lines;
    this.position = lines.geometry.attributes.position;
    this.color = lines.geometry.attributes.color;
    this.n = 0;
  }
  segment(a, b, color) {
    for (const p of [a, b]) {
      this.position.setXYZ(this.n, p.x, p.y, p.z);
      this.color.setXYZ(this.n, color.r, color.g, color.b);
      ++this.n;
    }
  }
  done() {
    const geometry = this.lines.geometry;
    geometry.setDrawRange(0, this.n);
    this.position.needsUpdate = true;
    this.color.needsUpdate = true;
    // three.js bounds a geometry by its whole buffer, whatever the draw range: the slots not drawn
    // repeat the first vertex, so that the bounds (fitting the camera, picking, culling) are those
    // of what is drawn; with nothing drawn they are empty.
    if (this.n === 0) {
      geometry.boundingBox = new THREE.Box3();
      geometry.boundingSphere = new THREE.Sphere(new THREE.Vector3(), -1);
      return;
    }
    const [x, y, z] = [this.position.getX(0), this.position.getY(0), this.position.getZ(0)];
    for (let i = this.n; i < this.position.count; ++i) this.position.setXYZ(i, x, y, z);
    geometry.boundingBox = null;  // recomputed when asked
    geometry.boundingSphere = null;
  }
}

function instances(geometry, count, renderOrder) {
  const mesh = new THREE.InstancedMesh(geometry, new THREE.MeshBasicMaterial({ depthTest: false }), count);
  mesh.instanceMatrix.setUsage(THREE.DynamicDrawUsage);
  // Made now, so that the shader is compiled with per-instance colours from the first frame.
  mesh.instanceColor = new THREE.InstancedBufferAttribute(new Float32Array(3 * count), 3).setUsage(THREE.DynamicDrawUsage);
  mesh.renderOrder = renderOrder;  // drawn over the links: a frame inside a solid link still shows
  mesh.matrixAutoUpdate = false;
  return mesh;
}

export class Overlays {
  // links: {X_SF, comLocal, color, box (inertia.js equivalentBox or null), X_FB}; joints: {link,
  // axis (unit, in the link's frame F), type, highlighted}; size: the model's size (m).
  constructor(size, links, joints) {
    this.size = size;
    this.links = links;
    this.joints = joints;
    this.frameLines = lineSegments(6 * links.length + 2 * joints.length, false);
    this.frameLines.renderOrder = 2;
    const cone = new THREE.CylinderGeometry(0, 0.5, 1, 5, 1).translate(0, -0.5, 0);  // ArrowHelper's head
    this.heads = instances(cone, Math.max(joints.length, 1), 2);
    this.comSpheres = instances(new THREE.SphereGeometry(1, 12, 8), links.length + 1, 3);
    this.boxLines = lineSegments(24 * links.length, true);
    // The groups the page's toggles show and hide.
    this.frames = new THREE.Group();
    this.frames.add(this.frameLines, this.heads);
    this.coms = new THREE.Group();
    this.coms.add(this.comSpheres);
    this.boxes = new THREE.Group();
    this.boxes.add(this.boxLines);
  }

  // Places and colours everything from the links' X_SF, the joints' highlight and the total
  // centre of mass (a Vector3 in S).
  update(totalCom) {
    const s = this.size;
    const p = new THREE.Vector3(), q = new THREE.Vector3();
    const frames = new LineWriter(this.frameLines);
    for (const link of this.links) {
      p.setFromMatrixPosition(link.X_SF);
      AXIS_COLORS.forEach((color, i) => {
        q.set(0, 0, 0).setComponent(i, 0.08 * s).applyMatrix4(link.X_SF);
        frames.segment(p, q, color);
      });
    }
    // Each joint's axis: an arrow from its frame's origin, as long as 0.15 of the model (a fixed
    // joint's only when a diagnostic names it).
    const length = 0.15 * s, headLength = 0.04 * s, headWidth = 0.02 * s;
    const turn = new THREE.Quaternion(), head = new THREE.Matrix4();
    let shown = 0;
    for (const j of this.joints) {
      if (j.type === 'fixed' && !j.highlighted) continue;
      const color = j.highlighted ? RED : AXIS_CYAN;
      p.setFromMatrixPosition(j.link.X_SF);
      q.copy(j.axis).multiplyScalar(length - headLength).applyMatrix4(j.link.X_SF);
      frames.segment(p, q, color);
      turn.setFromUnitVectors(Y, j.axis);
      head.compose(j.axis.clone().multiplyScalar(length), turn, new THREE.Vector3(headWidth, headLength, headWidth));
      this.heads.setMatrixAt(shown, head.premultiply(j.link.X_SF));
      this.heads.setColorAt(shown, color);
      ++shown;
    }
    frames.done();
    this.heads.count = shown;
    this.heads.visible = shown > 0;
    this.touched(this.heads);

    const sphere = new THREE.Matrix4();
    this.links.forEach((link, i) => {
      p.fromArray(link.comLocal).applyMatrix4(link.X_SF);
      this.comSpheres.setMatrixAt(i, sphere.makeScale(0.012 * s, 0.012 * s, 0.012 * s).setPosition(p));
      this.comSpheres.setColorAt(i, COM_YELLOW);
    });
    // The whole model's centre of mass last, so that it is drawn over the links' own.
    const n = this.links.length;
    this.comSpheres.setMatrixAt(n, sphere.makeScale(0.025 * s, 0.025 * s, 0.025 * s).setPosition(totalCom));
    this.comSpheres.setColorAt(n, TOTAL_MAGENTA);
    this.touched(this.comSpheres);

    const boxes = new LineWriter(this.boxLines);
    const X_SB = new THREE.Matrix4();
    const corners = Array.from({ length: 8 }, () => new THREE.Vector3());
    for (const link of this.links) {
      if (!link.box) continue;
      X_SB.multiplyMatrices(link.X_SF, link.X_FB);
      const [a, b, c] = link.box.sides.map((x) => Math.max(x, 1e-6) / 2);
      corners.forEach((v, k) => v.set(k & 1 ? a : -a, k & 2 ? b : -b, k & 4 ? c : -c).applyMatrix4(X_SB));
      for (const [i, k] of BOX_EDGES) boxes.segment(corners[i], corners[k], link.color);
    }
    boxes.done();
  }

  // Where link i's centre-of-mass sphere is drawn (i = links.length: the whole model's), in S:
  // read back from the instance that draws it, for the test hook.
  comDrawn(i) {
    const m = new THREE.Matrix4();
    this.comSpheres.getMatrixAt(i, m);
    return new THREE.Vector3().setFromMatrixPosition(m).toArray();
  }

  touched(mesh) {
    mesh.instanceMatrix.needsUpdate = true;
    if (mesh.instanceColor) mesh.instanceColor.needsUpdate = true;
    mesh.boundingBox = null;
    mesh.boundingSphere = null;
  }
}
