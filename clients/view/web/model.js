// One revision of one model drawn in three.js: its RDTF glTF (GLTFLoader, geometry from the blobs
// rdtf-view serves), each link tinted apart and moved by LINK_STATE, joint frames and axes,
// centres of mass, equivalent-inertia boxes, and the links and joints diagnostics name in red.
//
// Frames: `root` is the model in its scene frame S (glTF, Y up). A link's frame F (LINK_STATE's
// pose, the joint frame of docs/format.md) is the frame of its frame node with scale removed: the
// joint node nearest the link that has a transform of its own or joint keys in its extras, else
// the link node. At load, X_FL = inv(X_SF0) X_SL0 ties the link node L to F; every link node is
// then re-parented to `root` and drawn at X_SL = X_SF X_FL, with X_SF from LINK_STATE (or X_SF0).
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { equivalentBox } from './inertia.js';
import { Overlays } from './overlays.js';
import { glbOf, loadRevisionFiles } from './files.js';

const now = () => performance.timeOrigin + performance.now();

const JOINT_KEYS = ['rdtf_joint', 'rdtf_axis', 'rdtf_lower', 'rdtf_upper', 'rdtf_effort', 'rdtf_velocity',
  'rdtf_damping', 'rdtf_friction', 'rdtf_spring_stiffness'];
const RED = new THREE.Color(0xff2020);

function hasOwnTransform(node) {
  const t = node.translation, r = node.rotation, s = node.scale;
  return (node.matrix && node.matrix.some((x, i) => x !== (i % 5 === 0 ? 1 : 0))) ||
    (t && t.some((x) => x !== 0)) || (r && (r[0] !== 0 || r[1] !== 0 || r[2] !== 0 || r[3] !== 1)) ||
    (s && s.some((x) => x !== 1));
}
function hasJointKeys(node) {
  return !!node.extras && JOINT_KEYS.some((k) => k in node.extras);
}
// The rigid part of a matrix (scale removed).
function rigid(matrix) {
  const p = new THREE.Vector3(), q = new THREE.Quaternion(), s = new THREE.Vector3();
  matrix.decompose(p, q, s);
  return new THREE.Matrix4().compose(p, q, new THREE.Vector3(1, 1, 1));
}

export class ModelView {
  constructor(info) {
    this.info = info;
    this.id = info.id;
    this.revision = info.revision;
    this.root = new THREE.Group();
    this.root.name = `model ${info.id} r${info.revision}`;
    this.links = [];  // {name, gltf_name, node, object, X_FL, X_SF, color, meshes, box, X_FB}
    this.joints = [];  // {name, type, lower, upper, axis, link, highlighted}
    this.jointPositions = new Map();
    this.simTime = null;
    this.highlighted = { links: [], joints: [] };
    this.hashes = new Set((info.files || []).map((f) => f.sha256));  // the contents it draws from
    this.timing = { ...(info.timing || {}) };
  }

  // Fetches the revision's files (each content once, files.js) and parses them; `timing` gets
  // when the files were in (fetched_at) and when GLTFLoader was done (parsed_at), ms since the epoch.
  async load() {
    const files = await loadRevisionFiles(this.info);
    this.timing.fetched_at = now();
    const source = files.bin ? glbOf(files.json, files.bin) : JSON.stringify(files.json);
    let gltf;
    try {
      gltf = await new GLTFLoader().parseAsync(source, files.resourcePath);
    } finally {
      files.urls.forEach((url) => URL.revokeObjectURL(url));  // the images are decoded by now
    }
    this.timing.parsed_at = now();
    // Textures drawn with their image (GLTFLoader draws a material whose image did not load
    // without it, and says so only on the console).
    const maps = new Set();
    gltf.scene.traverse((o) => {
      for (const m of o.material ? [o.material].flat() : []) if (m.map && m.map.image && m.map.image.width > 0) maps.add(m.map);
    });
    this.texturesDrawn = maps.size;
    const json = gltf.parser.json;
    const nodeObjects = [];
    for (const [object, where] of gltf.parser.associations) {
      if (where && where.nodes !== undefined && object.isObject3D) nodeObjects[where.nodes] = object;
    }
    this.root.add(gltf.scene);
    this.root.updateMatrixWorld(true);
    const parent = [];
    (json.nodes || []).forEach((n, i) => (n.children || []).forEach((c) => { parent[c] = i; }));
    const linkNodes = new Set(this.info.links.map((l) => l.node));
    this.nodeNames = (json.nodes || []).map((n) => n.name || '');
    const rdtf = (json.extras && json.extras.RDTF && json.extras.RDTF.nodes) || [];
    this.rdtfNodes = new Map(rdtf.map((e) => [e.node, e]));
    this.size = 0;

    this.info.links.forEach((l, index) => {
      const object = nodeObjects[l.node];
      if (!object) throw new Error(`link ${l.name}: no node ${l.node} in the glTF`);
      const chain = [];
      let p = parent[l.node];
      while (p !== undefined && !linkNodes.has(p)) { chain.push(p); p = parent[p]; }
      // The link frame as rdtf finds it (docs/format.md, "The joint frame is the pivot the
      // modeller placed"; core/robot/robot.cc): the joint node nearest the link with a transform
      // of its own or joint keys, else the link node; but the link node itself where it carries
      // the joint keys below joint nodes that carry none (unless an extras.RDTF entry between
      // names another joint type: its keys are stale), or where it is a frame link (no mesh,
      // only inertial or visual nodes below) on a fixed joint.
      let frameNode = l.node;
      if (p !== undefined) {
        const own = json.nodes[l.node];
        const ownType = own.extras ? own.extras.rdtf_joint : undefined;
        const stale = chain.some((n) => {
          const e = this.rdtfNodes.get(n);
          return e && e.joint && ownType !== undefined && e.joint.type !== ownType;
        });
        const ownPivot = hasJointKeys(own) && !chain.some((n) => hasJointKeys(json.nodes[n])) && !stale;
        const joint = (this.info.joints || []).find((j) => j.child === l.name);
        const frameLink = joint && joint.type === 'fixed' && own.mesh === undefined &&
          (own.children || []).every((c) => { const e = this.rdtfNodes.get(c); return !e || e.type === 'inertial' || e.type === 'visual'; });
        const placed = chain.find((n) => hasOwnTransform(json.nodes[n]) || hasJointKeys(json.nodes[n]));
        if (!ownPivot && !frameLink && placed !== undefined) frameNode = placed;
      }
      const X_SF0 = rigid(nodeObjects[frameNode].matrixWorld);
      const X_FL = X_SF0.clone().invert().multiply(object.matrixWorld);
      this.links.push({ ...l, index, object, chain, frameNode, X_FL, X_SF: X_SF0.clone(), meshes: [], comLocal: l.com });
    });
    // Every link node straight under root (attach keeps its world transform), drawn from X_SF.
    for (const link of this.links) {
      this.root.attach(link.object);
      link.object.matrixAutoUpdate = false;
    }
    // Tint each link apart (golden-ratio hues) on its own copies of the materials.
    const box = new THREE.Box3();
    for (const link of this.links) {
      link.color = new THREE.Color().setHSL((link.index * 0.618034) % 1, 0.55, 0.55);
      link.object.traverse((o) => {
        if (o !== link.object && this.links.some((other) => other.object === o)) return;
        if (!o.isMesh) return;
        o.material = (Array.isArray(o.material) ? o.material[0] : o.material).clone();
        o.material.color = link.color.clone();
        o.userData.rdtfLink = link.name;
        link.meshes.push(o);
        box.expandByObject(o);
      });
      // The link's geometry in its own node's frame, whatever the pose (the test hook's bounds).
      const X_LW = link.object.matrixWorld.clone().invert();
      link.bounds = new THREE.Box3();
      for (const mesh of link.meshes) {
        if (!mesh.geometry.boundingBox) mesh.geometry.computeBoundingBox();
        link.bounds.union(mesh.geometry.boundingBox.clone().applyMatrix4(X_LW.clone().multiply(mesh.matrixWorld)));
      }
    }
    this.size = box.isEmpty() ? 1 : box.getSize(new THREE.Vector3()).length();
    this.buildBoxes();
    this.buildJoints();
    this.overlays = new Overlays(this.size, this.links, this.joints);
    this.root.add(this.overlays.frames, this.overlays.coms, this.overlays.boxes);
    this.applyPose();
    this.timing.built_at = now();
  }

  // Each link's equivalent-inertia box (inertia.js) and its pose X_FB in the link's frame F.
  buildBoxes() {
    for (const link of this.links) {
      link.box = equivalentBox(link.mass, link.inertia);
      if (!link.box) continue;
      const [u, v, w] = link.box.axes.map((a) => new THREE.Vector3(...a));
      link.X_FB = new THREE.Matrix4().makeBasis(u, v, w).setPosition(...link.comLocal);
    }
  }

  buildJoints() {
    const byChild = new Map(this.links.map((l) => [l.name, l]));
    for (const j of this.info.joints || []) {
      const link = byChild.get(j.child);
      if (!link) continue;
      // The axis in the joint frame, glTF's axes: extras.RDTF's joint entry; else the URDF's axis
      // turned back from ROS's Z up (docs/urdf.md, "Frames": glTF (x, y, z) is URDF (x, -z, y)).
      const entry = [link.node, ...link.chain].map((n) => this.rdtfNodes.get(n)).find((e) => e && e.joint && e.joint.axis);
      const axis = entry ? entry.joint.axis : [j.axis[0], j.axis[2], -j.axis[1]];
      // The name the modeller gave it (diagnostics and hovers use it), which rdtfd sanitised into
      // the URDF name that states and commands carry: "elbow joint" is elbow_joint.
      const owner = [link.node, ...link.chain].find((n) => { const e = this.rdtfNodes.get(n); return e && e.joint; });
      this.joints.push({ ...j, link, axis: new THREE.Vector3(...axis).normalize(), highlighted: false,
        gltf_name: owner !== undefined && this.nodeNames[owner] ? this.nodeNames[owner] : j.name,
        gltf_names: link.chain.map((n) => this.nodeNames[n]) });
    }
  }

  // LINK_STATE of this revision (the hub's "links" part): every link's X_SF.
  // Whether any link moved. A model at rest streams the very same poses (100 a second by
  // default), and a frame for each would cost a software rasterizer what the next revision needs.
  setLinkState(links) {
    const byName = new Map(this.links.map((l) => [l.name, l]));
    let moved = false;
    links.names.forEach((name, i) => {
      const link = byName.get(name);
      if (!link) return;
      const pose = [...links.position[i], ...links.orientation[i]];
      if (link.pose && pose.length === link.pose.length && pose.every((v, k) => v === link.pose[k])) return;
      link.pose = pose;
      moved = true;
      const [x, y, z] = links.position[i];
      const [w, qx, qy, qz] = links.orientation[i];
      link.X_SF.compose(new THREE.Vector3(x, y, z), new THREE.Quaternion(qx, qy, qz, w), new THREE.Vector3(1, 1, 1));
    });
    this.simTime = links.sim_time;
    if (moved) this.applyPose();
    return moved;
  }

  setJointState(joints) {
    joints.names.forEach((name, i) => this.jointPositions.set(name, joints.position[i]));
  }

  applyPose() {
    let mass = 0;
    const com = new THREE.Vector3(), c = new THREE.Vector3();
    for (const link of this.links) {
      link.object.matrix.multiplyMatrices(link.X_SF, link.X_FL);
      link.object.matrixWorldNeedsUpdate = true;
      c.fromArray(link.comLocal).applyMatrix4(link.X_SF);
      mass += link.mass;
      com.addScaledVector(c, link.mass);
    }
    if (mass > 0) com.divideScalar(mass);
    this.totalMass = mass;
    this.totalComPosition = com;
    this.overlays.update(com);
  }

  // Diagnostics to red (infos are no fault; where there are errors, only they: a rejected save's culprit must not hide among
  // the warnings the model had before): each names a link or joint by the names quoted in its message, else by the node of its
  // JSON pointer (/nodes/N: a link node, or a joint node between two links).
  highlight(diagnostics) {
    for (const link of this.links) for (const m of link.meshes) m.material.color.copy(link.color);
    for (const j of this.joints) j.highlighted = false;
    const links = new Set(), joints = new Set();
    const faults = (diagnostics || []).filter((x) => x.severity !== 'info');
    const errors = faults.filter((x) => x.severity === 'error');
    for (const d of errors.length > 0 ? errors : faults) {
      const names = [...(d.message || '').matchAll(/'([^']+)'/g)].map((m) => m[1]);
      const node = /^\/nodes\/(\d+)/.exec(d.pointer || '');
      const nodeIndex = node ? Number(node[1]) : -1;
      let found = false;
      for (const j of this.joints) {
        if (names.includes(j.name) || names.some((n) => j.gltf_names.includes(n)) || j.link.chain.includes(nodeIndex)) {
          joints.add(j);
          found = true;
        }
      }
      for (const link of this.links) {
        if ((names.includes(link.name) || names.includes(link.gltf_name) || link.node === nodeIndex) && !found) {
          links.add(link);
        }
      }
    }
    for (const j of joints) {
      j.highlighted = true;  // its arrow red, and shown if fixed
      links.add(j.link);  // the part the joint moves, so that it shows in red too
    }
    for (const link of links) for (const m of link.meshes) m.material.color.copy(RED);
    this.highlighted = { links: [...links].map((l) => l.name), joints: [...joints].map((j) => j.name) };
    this.overlays.update(this.totalComPosition);
  }

  setVisible(parts) {
    this.overlays.frames.visible = parts.frames;
    this.overlays.coms.visible = parts.com;
    this.overlays.boxes.visible = parts.inertia;
  }

  state() {
    return {
      links: this.links.map((l) => {
        const p = new THREE.Vector3().setFromMatrixPosition(l.X_SF);
        const n = new THREE.Vector3().setFromMatrixPosition(l.object.matrix);  // the link node, as drawn
        return { name: l.name, position: [p.x, p.y, p.z], node_position: [n.x, n.y, n.z], box: l.box ? l.box.sides : null,
          com_drawn: this.overlays.comDrawn(l.index), meshes: l.meshes.length,
          bounds: l.bounds.isEmpty() ? null : [l.bounds.min.toArray(), l.bounds.max.toArray()] };
      }),
      joints: this.joints.map((j) => ({ name: j.name, gltf_name: j.gltf_name, type: j.type, lower: j.lower, upper: j.upper,
        position: this.jointPositions.has(j.name) ? this.jointPositions.get(j.name) : null,
        kp: j.kp ?? null, kd: j.kd ?? null, moved_inertia: j.moved_inertia ?? null })),
      total_mass: this.totalMass,
      com: this.totalComPosition.toArray(),
      sim_time: this.simTime,
      highlighted: this.highlighted,
      textures: this.texturesDrawn,
    };
  }

  dispose() {
    this.root.traverse((o) => {
      if (o.isInstancedMesh) o.dispose();  // its instance buffers
      if (o.geometry) o.geometry.dispose();
      for (const m of o.material ? [o.material].flat() : []) {
        // A texture's GPU copy and its ImageBitmap are freed only when asked (the links' tinted
        // copies of a material share its texture: disposing it twice is harmless).
        if (m.map) {
          m.map.dispose();
          if (m.map.image && typeof m.map.image.close === 'function') m.map.image.close();
        }
        m.dispose();
      }
    });
  }
}
