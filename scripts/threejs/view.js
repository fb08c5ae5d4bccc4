// The page's module: loads the glb and its lightmap EXRs, draws them unlit with MeshBasicMaterial, and reports
// the canvas as a PNG. See view.html for the query parameters.
//
// What each surface shows (linear, before tone mapping), with L the lightmap texel bilinearly filtered at
// TEXCOORD_1 (extras.lightmap.texCoord):
//   baseColorFactor × baseColorTexture(TEXCOORD_0) × L          (quantity "irradiance/pi": L = E/π)
//   + emissiveFactor × KHR_materials_emissive_strength          on an emitter's front faces
// as src/lightmap/view.rs has it. An emitter without extras.lightmap shows its emission alone; a material with
// neither is an error.
// MeshBasicMaterial's fragment shader (three/src/renderers/shaders/ShaderLib/meshbasic.glsl.js) computes
//   reflectedLight.indirectDiffuse += lightMapTexel.rgb * lightMapIntensity * RECIPROCAL_PI;
//   reflectedLight.indirectDiffuse *= diffuseColor.rgb;
// so lightMapIntensity = π shows albedo × L for "irradiance/pi" (and 1 would suit a lightmap of E itself).
// LinearToneMapping is saturate(toneMappingExposure × color) (ShaderChunk/tonemapping_pars_fragment.glsl.js),
// followed by the sRGB transfer function for SRGBColorSpace output.

import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { EXRLoader } from 'three/examples/jsm/loaders/EXRLoader.js';

const out = document.getElementById('out');
const errorBox = document.getElementById('error');
const infoBox = document.getElementById('info');
const params = new URLSearchParams(location.search);
const report = params.get('report');
let finished = false;

async function finish(result) {
    if (finished) return;
    finished = true;
    if (result.error !== undefined) {
        errorBox.textContent = result.error;
        document.title = 'error';
    } else {
        infoBox.textContent = JSON.stringify(result.info);
        out.textContent = result.png;
        document.title = 'done';
    }
    if (report) {
        try {
            await fetch(report, { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(result) });
        } catch (e) {
            console.error('cannot report the result to ' + report + ': ' + e);
        }
    }
}

function fail(message) {
    return finish({ error: String(message).replace(/\s+/g, ' ').trim() });
}

window.addEventListener('error', (e) => fail('page error: ' + (e.error && e.error.message ? e.error.message : e.message)));
window.addEventListener('unhandledrejection', (e) => fail('page error: ' + (e.reason && e.reason.message ? e.reason.message : e.reason)));

function positiveNumber(name, fallback) {
    const text = params.get(name);
    if (text === null || text === '') return fallback;
    const value = Number(text);
    if (!Number.isFinite(value) || value <= 0) throw new Error(`query parameter ${name}=${text} is not a positive number`);
    return value;
}

// EXRLoader stores the EXR's bottom row first (it writes EXR row y to data row height - 1 - y, and returns
// flipY: false), so uv v = 0 would sample the EXR's bottom row. glTF's v = 0 is the image's top (EXR row 0),
// which is also how GLTFLoader's own textures are sampled (flipY = false, image row 0 at v = 0): put the rows
// back in file order.
function flipRows(texture) {
    const { data, width, height } = texture.image;
    const row = data.length / height;
    if (!Number.isInteger(row) || row % width !== 0) throw new Error(`lightmap data of ${data.length} values is not ${height} rows of ${width} texels`);
    const scratch = new data.constructor(row);
    for (let top = 0, bottom = height - 1; top < bottom; top++, bottom--) {
        scratch.set(data.subarray(top * row, (top + 1) * row));
        data.copyWithin(top * row, bottom * row, (bottom + 1) * row);
        data.set(scratch, bottom * row);
    }
}

// A lightmap page: one EXR file (its first part), its R, G, B channels (A is not used).
function loadLightmap(url) {
    return new Promise((resolve, reject) => {
        const loader = new EXRLoader();
        // Half floats: filterable in every WebGL2 (32-bit floats need OES_texture_float_linear).
        loader.setDataType(THREE.HalfFloatType);
        loader.load(url, (texture, texData) => {
            try {
                flipRows(texture);
                texture.flipY = false;
                texture.colorSpace = THREE.LinearSRGBColorSpace;
                texture.needsUpdate = true;
                resolve({ texture, header: texData.header });
            } catch (e) {
                reject(e);
            }
        }, undefined, (e) => reject(new Error(`cannot load lightmap ${url}: ${e && e.message ? e.message : e}`)));
    });
}

const INTENSITY = { 'irradiance/pi': Math.PI, irradiance: 1 };

// MeshBasicMaterial has no emissive term: an emitter that also has a lightmap gets its emission added to the
// lightmapped colour in the fragment shader, on front faces only (what sensorlight's emitters emit from).
function addEmission(material, emission) {
    material.onBeforeCompile = (shader) => {
        const before = 'vec3 outgoingLight = reflectedLight.indirectDiffuse;';
        if (!shader.fragmentShader.includes(before)) throw new Error('three.js\'s meshbasic shader changed: cannot add emission to it');
        shader.uniforms.sensorlightEmission = { value: emission };
        shader.fragmentShader = 'uniform vec3 sensorlightEmission;\n' + shader.fragmentShader.replace(before,
            'vec3 outgoingLight = reflectedLight.indirectDiffuse + ( gl_FrontFacing ? sensorlightEmission : vec3( 0.0 ) );');
    };
    material.customProgramCacheKey = () => 'sensorlight-emission';
}

async function main() {
    const glbParam = params.get('glb');
    if (!glbParam) throw new Error('no glb query parameter');
    const width = Math.round(positiveNumber('width', 640));
    const height = Math.round(positiveNumber('height', 480));
    const exposure = positiveNumber('exposure', 1);
    const glbUrl = new URL(glbParam, location.href).href;

    let renderer;
    try {
        const canvas = document.createElement('canvas');
        canvas.width = width;
        canvas.height = height;
        document.body.appendChild(canvas);
        renderer = new THREE.WebGLRenderer({ canvas, antialias: false, alpha: false, preserveDrawingBuffer: true, powerPreference: 'high-performance' });
    } catch (e) {
        throw new Error('WebGL unavailable: ' + (e && e.message ? e.message : e));
    }
    renderer.setPixelRatio(1);
    renderer.setSize(width, height, false);
    renderer.outputColorSpace = THREE.SRGBColorSpace;
    renderer.toneMapping = THREE.LinearToneMapping;
    renderer.toneMappingExposure = exposure;
    renderer.setClearColor(0x000000, 1);

    const t0 = performance.now();
    let gltf;
    try {
        gltf = await new GLTFLoader().loadAsync(glbUrl);
    } catch (e) {
        throw new Error(`cannot load ${glbUrl}: ${e && e.message ? e.message : e}`);
    }
    if (gltf.cameras.length !== 1) throw new Error(`the glb holds ${gltf.cameras.length} cameras, not one`);
    const camera = gltf.cameras[0];
    if (!camera.isPerspectiveCamera) throw new Error('the glb\'s camera is not perspective');
    let root = camera;
    while (root.parent) root = root.parent;
    if (root !== gltf.scene) throw new Error('the glb\'s camera is not on a node of its default scene');

    // Every lightmap file the materials name (one per page: "page" only says which), loaded once.
    const meshes = [];
    gltf.scene.traverse((o) => { if (o.isMesh) meshes.push(o); });
    if (meshes.length === 0) throw new Error('the glb has no meshes');
    const lightmaps = new Map();
    for (const mesh of meshes) {
        const lm = mesh.material.userData && mesh.material.userData.lightmap;
        if (!lm) continue;
        if (typeof lm.uri !== 'string') throw new Error(`material "${mesh.material.name}": extras.lightmap has no uri`);
        if (!lightmaps.has(lm.uri)) lightmaps.set(lm.uri, loadLightmap(new URL(lm.uri, glbUrl).href));
    }
    const loaded = new Map();
    for (const [key, promise] of lightmaps) loaded.set(key, await promise);

    // One texture per (lightmap, uv channel); clones share the data.
    const byChannel = new Map();
    function lightmapTexture(key, channel) {
        const k = `${key}@${channel}`;
        if (!byChannel.has(k)) {
            const entry = loaded.get(key);
            const texture = entry.taken ? entry.texture.clone() : entry.texture;
            entry.taken = true;
            texture.channel = channel;
            texture.needsUpdate = true;
            byChannel.set(k, texture);
        }
        return byChannel.get(k);
    }

    const replaced = new Map();
    let emitters = 0;
    let lightmapped = 0;
    for (const mesh of meshes) {
        const source = mesh.material;
        if (Array.isArray(source)) throw new Error(`mesh "${mesh.name}" has several materials`);
        if (!replaced.has(source)) {
            const name = source.name;
            const emission = source.emissive ? source.emissive.clone().multiplyScalar(source.emissiveIntensity ?? 1) : new THREE.Color(0, 0, 0);
            const emits = Math.max(emission.r, emission.g, emission.b) > 0;
            if (emits && source.emissiveMap) throw new Error(`material "${name}": an emissiveTexture is more than this harness shows`);
            const lm = source.userData && source.userData.lightmap;
            const material = new THREE.MeshBasicMaterial({
                name,
                side: source.side,
                transparent: source.transparent,
                opacity: source.opacity,
                alphaTest: source.alphaTest,
            });
            if (lm) {
                if ((lm.encoding ?? 'linear') !== 'linear') throw new Error(`material "${name}": lightmap encoding "${lm.encoding}" is not "linear"`);
                const intensity = INTENSITY[lm.quantity ?? 'irradiance/pi'];
                if (intensity === undefined) throw new Error(`material "${name}": lightmap quantity "${lm.quantity}" is not one of ${Object.keys(INTENSITY).join(', ')}`);
                const channel = lm.texCoord ?? 1;
                if (!Number.isInteger(channel) || channel < 0 || channel > 3) throw new Error(`material "${name}": lightmap texCoord ${lm.texCoord} is not 0..3`);
                material.color.copy(source.color);
                material.vertexColors = source.vertexColors;
                material.map = source.map || null;
                material.lightMap = lightmapTexture(lm.uri, channel);
                material.lightMapIntensity = intensity;
                if (emits) addEmission(material, emission);
                lightmapped++;
            } else if (emits) {
                material.color.copy(emission);
            } else {
                throw new Error(`material "${name}" has no extras.lightmap and is no emitter`);
            }
            if (emits) emitters++;
            replaced.set(source, material);
        }
        const material = replaced.get(source);
        if (material.lightMap) {
            const uv = material.lightMap.channel === 0 ? 'uv' : `uv${material.lightMap.channel}`;
            if (!mesh.geometry.getAttribute(uv)) throw new Error(`mesh "${mesh.name}" (material "${source.name}") has no TEXCOORD_${material.lightMap.channel} for its lightmap`);
        }
        mesh.material = material;
    }

    camera.aspect = width / height;
    camera.updateProjectionMatrix();
    gltf.scene.updateMatrixWorld(true);
    const t1 = performance.now();
    renderer.render(gltf.scene, camera);
    const gl = renderer.getContext();
    const png = renderer.domElement.toDataURL('image/png');
    const t2 = performance.now();
    const glError = gl.getError();
    if (glError !== gl.NO_ERROR) throw new Error(`WebGL error 0x${glError.toString(16)} while drawing`);

    const debug = gl.getExtension('WEBGL_debug_renderer_info');
    return {
        png,
        info: {
            width, height, exposure,
            meshes: meshes.length,
            materials: { lightmapped, emitters },
            lightmaps: [...loaded].map(([key, { texture, header }]) => ({
                key, width: texture.image.width, height: texture.image.height, compression: header.compression,
            })),
            renderer: debug ? gl.getParameter(debug.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER),
            three: THREE.REVISION,
            load_ms: Math.round(t1 - t0),
            draw_ms: Math.round(t2 - t1),
        },
    };
}

main().then(finish, (e) => fail(e && e.message ? e.message : e));
