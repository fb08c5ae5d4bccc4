//! What an MTL material states that this renderer does not render. Every material is drawn as a diffuse
//! `Kd` (its colour texture `map_Kd` included, cut out by `map_d`) that emits `Ke` (times `map_Ke`)
//! (docs/DESIGN.md §1); a mirror, glass or another texture map would otherwise render as plain diffuse
//! without a word. [`Unrendered`] collects, per material, the statements that would have changed its
//! look, and says them once per material: `materials.mtl: material 'glass': Ni, Tf, illum 7 ignored
//! (treated as diffuse)`.
//!
//! Statements that change nothing are not said, so that common exporters' files load quietly:
//! - `Ka` (ambient: global illumination computes it) and `illum` 0–2 (colour; diffuse; diffuse and highlight,
//!   the highlight being `Ks`'s);
//! - `Ks` of zero, and `Ns` (the highlight's exponent) unless `Ks` is not zero;
//! - `Ni` (index of refraction) and `Tf` (transmission filter) on a material that transmits nothing: not
//!   refractive (`illum` 4, 6, 7, 9) and opaque (`d` 1, `Tr` 0). Blender writes `Ni 1.45` on every material,
//!   McGuire's Cornell box `Ni 1.5` on its walls;
//! - `d` 1 and `Tr` 0 (opaque), and the PBR extensions (`Pr`, `Pm`, …) at zero.
//!
//! Said: `Ks` not zero (and then `Ns`), `illum` 3–10 (reflection, glass, refraction, shadow matte), `d`
//! below 1 or `Tr` above 0 (transparency), `Ni` and `Tf` where the material transmits, PBR extensions not
//! zero, and every other statement: texture maps but `map_Kd`, `map_Ke` and `map_d` (`map_*`, `bump`,
//! `disp`, `decal`, `refl`, `norm`) and statements of no kind known here.

/// Statements read by the renderer, or harmless whatever their value.
const USED_OR_HARMLESS: &[&str] = &["newmtl", "Kd", "Ke", "Ka", "map_Kd", "map_Ke", "map_d"];
/// The PBR extension's scalars: harmless at zero.
const PBR_SCALARS: &[&str] = &["Pr", "Pm", "Ps", "Pc", "Pcr", "aniso", "anisor"];
/// `illum` models that transmit light through the surface.
const REFRACTIVE: &[u8] = &[4, 6, 7, 9];

/// The statements of the material being read, and the warnings of those read before.
#[derive(Default)]
pub struct Unrendered {
    current: Option<Material>,
    warnings: Vec<String>,
}

/// One material's statements that matter for the warning.
#[derive(Default)]
struct Material {
    name: String,
    specular: bool,
    shininess: bool,
    refraction_index: Option<f32>,
    transmission_filter: bool,
    dissolve: Option<f32>,
    transparency: Option<f32>,
    illum: Option<u8>,
    /// Other statements ignored, in file order, each once.
    others: Vec<String>,
}

impl Unrendered {
    pub fn new() -> Self {
        Self::default()
    }

    /// Notes one statement of an MTL file, checked already (numbers where numbers are due).
    pub fn statement(&mut self, file: &str, keyword: &str, args: &[&str]) {
        if keyword == "newmtl" {
            self.finish(file);
            self.current = Some(Material { name: args.join(" "), ..Material::default() });
            return;
        }
        // Before any `newmtl`: no material to attach it to, and tobj keeps nothing of it.
        let Some(m) = &mut self.current else { return };
        let number = |i: usize| args.get(i).and_then(|a| a.parse::<f32>().ok());
        match keyword {
            k if USED_OR_HARMLESS.contains(&k) => {}
            "Ks" => m.specular |= (0..3).any(|i| number(i).is_some_and(|v| v > 0.0)),
            "Ns" => m.shininess = true,
            "Ni" => m.refraction_index = number(0),
            "Tf" => m.transmission_filter = true,
            "d" => m.dissolve = number(0),
            "Tr" => m.transparency = number(0),
            "illum" => m.illum = args.first().and_then(|a| a.parse().ok()),
            k if PBR_SCALARS.contains(&k) && number(0).is_some_and(|v| v == 0.0) => {}
            other => {
                if !m.others.iter().any(|o| o == other) {
                    m.others.push(other.to_owned());
                }
            }
        }
    }

    /// The warnings, once the whole file was read.
    pub fn warnings(mut self, file: &str) -> Vec<String> {
        self.finish(file);
        self.warnings
    }

    fn finish(&mut self, file: &str) {
        let Some(m) = self.current.take() else { return };
        let ignored = m.ignored();
        if !ignored.is_empty() {
            self.warnings.push(format!(
                "{file}: material '{}': {} ignored (treated as diffuse)",
                m.name,
                ignored.join(", ")
            ));
        }
    }
}

impl Material {
    /// The statements that would have changed the look, in the order Ks, Ns, Ni, Tf, d, Tr, illum, others.
    fn ignored(&self) -> Vec<String> {
        let refractive = self.illum.is_some_and(|i| REFRACTIVE.contains(&i));
        let transparent = self.dissolve.is_some_and(|d| d < 1.0) || self.transparency.is_some_and(|t| t > 0.0);
        let transmits = refractive || transparent;
        let mut out: Vec<String> = Vec::new();
        let mut say = |when: bool, what: &str| {
            if when {
                out.push(what.to_owned());
            }
        };
        say(self.specular, "Ks");
        say(self.specular && self.shininess, "Ns");
        say(transmits && self.refraction_index.is_some_and(|n| n != 1.0), "Ni");
        say(transmits && self.transmission_filter, "Tf");
        say(self.dissolve.is_some_and(|d| d < 1.0), "d");
        say(self.transparency.is_some_and(|t| t > 0.0), "Tr");
        if let Some(illum) = self.illum.filter(|&i| i >= 3) {
            out.push(format!("illum {illum}"));
        }
        out.extend(self.others.iter().cloned());
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The warnings for an MTL text, one statement a line.
    fn warnings(text: &str) -> Vec<String> {
        let mut u = Unrendered::new();
        for line in text.lines() {
            let words: Vec<&str> = line.split_whitespace().collect();
            if let Some((keyword, args)) = words.split_first() {
                u.statement("materials.mtl", keyword, args);
            }
        }
        u.warnings("materials.mtl")
    }

    #[test]
    fn mirrors_glass_and_maps_are_said_once_per_material() {
        let text = "newmtl glass\nKd 0.1 0.1 0.1\nNi 1.5\nTf 0.9 0.9 0.9\nillum 7\nillum 7\n\
                    newmtl mirror\nKs 0.9 0.9 0.9\nNs 200\nillum 3\n\
                    newmtl wood\nKd 0.5 0.3 0.1\nmap_Kd wood.png\nbump wood_n.png\nmap_Ks shine.png\nbump wood2.png\n\
                    newmtl veil\nd 0.4\nNi 1.33\n\
                    newmtl metal\nPm 1\nPr 0.2\n";
        assert_eq!(
            warnings(text),
            [
                "materials.mtl: material 'glass': Ni, Tf, illum 7 ignored (treated as diffuse)",
                "materials.mtl: material 'mirror': Ks, Ns, illum 3 ignored (treated as diffuse)",
                "materials.mtl: material 'wood': bump, map_Ks ignored (treated as diffuse)",
                "materials.mtl: material 'veil': Ni, d ignored (treated as diffuse)",
                "materials.mtl: material 'metal': Pm, Pr ignored (treated as diffuse)",
            ]
        );
    }

    /// What exporters write on plain diffuse materials says nothing: McGuire's walls, Blender's defaults.
    #[test]
    fn harmless_defaults_are_not_said() {
        let mcguire = "newmtl leftWall\nNs 10.0000\nNi 1.5000\nillum 2\nKa 0.63 0.065 0.05\nKd 0.63 0.065 0.05\n\
                       Ks 0 0 0\nKe 0 0 0\n";
        let blender_like = "newmtl Material\nNs 250\nKa 1 1 1\nKd 0.8 0.8 0.8\nKs 0 0 0\nKe 0 0 0\nNi 1.45\nd 1\n\
                            Tr 0\nTf 1 1 1\nillum 1\nPr 0\nPm 0\n";
        assert!(warnings(mcguire).is_empty(), "{:?}", warnings(mcguire));
        assert!(warnings(blender_like).is_empty(), "{:?}", warnings(blender_like));
        assert!(warnings("Ks 1 1 1\nillum 5\n").is_empty(), "no material: nothing to name");
    }
}
