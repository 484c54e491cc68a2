//! A scene as read, before anything is built (pbrt-v4's `BasicSceneBuilder` → `BasicScene`).
//!
//! The parser's directives are walked here with pbrt's graphics state — the transform, the attribute stack,
//! the current material, area light and media, named coordinate systems, the object being defined — into
//! entities: each statement's type, parameters and `file:line:col`, with the state it was given in. Names are
//! resolved as pbrt-v4 resolves them (a `NamedMaterial` to the definition read so far; media, objects and
//! coordinate systems must be defined before use), and a statement that cannot be read is refused here, at its
//! place. Nothing is built and no file but the scene's is opened: `build` creates cameras, films, media,
//! textures, materials, shapes and lights from this, one small `create` per kind.
//!
//! Invariant: each list keeps file order, and the world's shapes, instances and lights share one list
//! ([`World`]), because the order in which primitives and lights are made is their index, and the index is what
//! the samplers draw (a reordered scene renders another image of the same noise level).

use super::{err, Error};
use crate::render::scene::Overrides;
use firemedium_pbrt_parser::{Directive, Loc, Param, ParamDict, Target};
use glam::{DMat4, DVec3};
use std::collections::HashMap;

/// One statement as read: its type (or class), its parameters, where it was written, and its place in the
/// scene's order (for reporting what is found about it in that order).
#[derive(Debug, Clone)]
pub(super) struct Entity {
    pub(super) ty: String,
    pub(super) params: Vec<Param>,
    pub(super) loc: Loc,
    pub(super) order: usize,
}

/// The `Camera` statement, its camera-from-world transform and the medium it sits in (a name, or "").
#[derive(Debug, Clone)]
pub(super) struct Camera {
    pub(super) entity: Entity,
    pub(super) camera_from_world: DMat4,
    pub(super) medium: String,
}

/// `MakeNamedMedium`: the entity's type is its `string type` (or "").
#[derive(Debug, Clone)]
pub(super) struct Medium {
    pub(super) name: String,
    pub(super) entity: Entity,
    pub(super) ctm: DMat4,
}

/// `Texture`: the entity's type is its class.
#[derive(Debug, Clone)]
pub(super) struct Texture {
    pub(super) name: String,
    pub(super) entity: Entity,
}

/// `Material` (no name) or `MakeNamedMaterial`: the entity's type is the material's type.
#[derive(Debug, Clone)]
pub(super) struct Material {
    pub(super) name: Option<String>,
    pub(super) entity: Entity,
}

/// The material a shape is given: pbrt's default (diffuse 0.5) or a material statement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum MaterialRef {
    Default,
    Entity(usize),
}

/// A `Shape` with the graphics state it was given in.
#[derive(Debug, Clone)]
pub(super) struct Shape {
    pub(super) entity: Entity,
    pub(super) ctm: DMat4,
    pub(super) reverse: bool,
    pub(super) material: MaterialRef,
    /// Its area light (an index into [`Description::area_lights`]).
    pub(super) area: Option<usize>,
    pub(super) inside: String,
    pub(super) outside: String,
}

/// A statement of the world that makes primitives or lights, in file order.
#[derive(Debug, Clone)]
pub(super) enum World {
    Shape(Shape),
    /// `ObjectInstance`: an index into [`Description::objects`], its name, its transform.
    Instance {
        object: usize,
        name: String,
        ctm: DMat4,
        loc: Loc,
        order: usize,
    },
    /// `LightSource`, with its transform.
    Light {
        entity: Entity,
        ctm: DMat4,
    },
}

/// `ObjectBegin` … `ObjectEnd`: the shapes between.
#[derive(Debug, Clone)]
pub(super) struct Object {
    pub(super) name: String,
    pub(super) shapes: Vec<Shape>,
}

/// What the command line sets instead of the scene (applied once, here: [`Description::apply`]).
#[derive(Debug, Clone, Default)]
pub(super) struct CommandLine {
    pub(super) res: Option<(usize, usize)>,
    pub(super) crop: Option<[f64; 4]>,
    pub(super) pixel_bounds: Option<[f64; 4]>,
    pub(super) spp: Option<usize>,
}

/// A scene as read.
#[derive(Debug, Clone, Default)]
pub(super) struct Description {
    pub(super) camera: Option<Camera>,
    pub(super) film: Option<Entity>,
    pub(super) sampler: Option<Entity>,
    pub(super) filter: Option<Entity>,
    pub(super) integrator: Option<Entity>,
    /// `Option "integer seed"` and `Option "bool disablepixeljitter"`.
    pub(super) seed: u64,
    pub(super) pixel_jitter: bool,
    pub(super) media: Vec<Medium>,
    pub(super) textures: Vec<Texture>,
    pub(super) materials: Vec<Material>,
    pub(super) area_lights: Vec<Entity>,
    pub(super) objects: Vec<Object>,
    pub(super) world: Vec<World>,
    pub(super) command_line: CommandLine,
    /// What reading found, with each statement's place in the order.
    pub(super) warnings: Vec<(usize, String)>,
}

impl Description {
    /// The command line's settings over the scene's.
    pub(super) fn apply(&mut self, ov: &Overrides) {
        self.command_line = CommandLine {
            res: ov.res,
            crop: ov.crop,
            pixel_bounds: ov.pixel_bounds,
            spp: ov.spp,
        };
    }
}

/// pbrt's graphics state.
#[derive(Clone)]
struct State {
    ctm: DMat4,
    reverse: bool,
    material: MaterialRef,
    area: Option<usize>,
    inside: String,
    outside: String,
}

/// Reads directives into a [`Description`] (a parser target: the scene is read as it is parsed).
pub(super) struct Reader {
    desc: Description,
    st: State,
    /// Saved states, with where each was saved (AttributeBegin, TransformBegin, ObjectBegin).
    stack: Vec<(State, Loc)>,
    named_coords: HashMap<String, DMat4>,
    named_materials: HashMap<String, usize>,
    objects: HashMap<String, usize>,
    /// The object being defined, and its shapes so far.
    open_object: Option<Object>,
    order: usize,
    /// The first statement refused (parsing stops there).
    refused: Option<Error>,
}

impl Default for Reader {
    fn default() -> Reader {
        Reader {
            desc: Description {
                pixel_jitter: true,
                ..Default::default()
            },
            st: State {
                ctm: DMat4::IDENTITY,
                reverse: false,
                material: MaterialRef::Default,
                area: None,
                inside: String::new(),
                outside: String::new(),
            },
            stack: Vec::new(),
            named_coords: HashMap::new(),
            named_materials: HashMap::new(),
            objects: HashMap::new(),
            open_object: None,
            order: 0,
            refused: None,
        }
    }
}

impl Target for Reader {
    fn directive(
        &mut self,
        d: Directive,
        loc: &Loc,
    ) -> Result<(), firemedium_pbrt_parser::ParseError> {
        match self.read(d, loc) {
            Ok(()) => Ok(()),
            Err(e) => {
                // Parsing stops at the first refused statement; `finish` returns it as the scene's error.
                let stop = firemedium_pbrt_parser::ParseError {
                    loc: loc.clone(),
                    message: e.to_string(),
                };
                self.refused = Some(e);
                Err(stop)
            }
        }
    }
}

impl Reader {
    /// The description, once the parse is over (`parsed`: the parser's result).
    pub(super) fn finish(
        mut self,
        parsed: Result<(), firemedium_pbrt_parser::ParseError>,
    ) -> Result<Description, Error> {
        if let Some(e) = self.refused.take() {
            return Err(e);
        }
        parsed?;
        if let Some((_, open)) = self.stack.last() {
            return Err(err(open, "AttributeBegin (or TransformBegin, ObjectBegin) without its End: the scene ends inside it"));
        }
        Ok(self.desc)
    }

    fn warn(&mut self, loc: &Loc, m: impl std::fmt::Display) {
        self.desc
            .warnings
            .push((self.order, format!("{loc}: warning: {m}")));
    }

    fn entity(&self, ty: String, params: Vec<Param>, loc: &Loc) -> Entity {
        Entity {
            ty,
            params,
            loc: loc.clone(),
            order: self.order,
        }
    }

    fn read(&mut self, d: Directive, loc: &Loc) -> Result<(), Error> {
        self.order += 1;
        let ctm = &mut self.st.ctm;
        match d {
            Directive::Identity => *ctm = DMat4::IDENTITY,
            Directive::Translate(v) => *ctm *= DMat4::from_translation(DVec3::from(v)),
            Directive::Scale(v) => *ctm *= DMat4::from_scale(DVec3::from(v)),
            Directive::Rotate(a, axis) => {
                *ctm *=
                    DMat4::from_axis_angle(DVec3::from(axis).normalize_or_zero(), a.to_radians())
            }
            Directive::LookAt(v) => *ctm *= look_at(&v),
            Directive::Transform(m) => *ctm = DMat4::from_cols_array(&m),
            Directive::ConcatTransform(m) => *ctm *= DMat4::from_cols_array(&m),
            Directive::CoordinateSystem(n) => {
                self.named_coords.insert(n, *ctm);
            }
            Directive::CoordSysTransform(n) => match self.named_coords.get(&n) {
                Some(m) => *ctm = *m,
                None => {
                    return Err(err(
                        loc,
                        format!("CoordSysTransform \"{n}\": no such coordinate system"),
                    ))
                }
            },
            Directive::TransformTimes(..) | Directive::ActiveTransform(_) => {
                self.warn(loc, "motion blur transforms are ignored (one shutter time)")
            }
            Directive::ReverseOrientation => self.st.reverse = !self.st.reverse,
            Directive::AttributeBegin | Directive::TransformBegin => {
                self.stack.push((self.st.clone(), loc.clone()))
            }
            Directive::AttributeEnd | Directive::TransformEnd => match self.stack.pop() {
                Some((s, _)) => self.st = s,
                None => return Err(err(loc, "AttributeEnd without AttributeBegin")),
            },
            Directive::Attribute(..) => self.warn(loc, "Attribute defaults are ignored"),
            Directive::ObjectBegin(_) | Directive::ObjectEnd | Directive::ObjectInstance(_) => {
                return self.object(d, loc)
            }
            Directive::Option(p) => match (p.name.as_str(), p.numbers(), p.bools()) {
                // pbrt-v4's options that change the image: the sampler's seed, and pixel samples at the pixels'
                // centres.
                ("seed", Some([v]), _) if v.fract() == 0.0 && *v >= 0.0 && *v < 2f64.powi(63) => self.desc.seed = *v as u64,
                ("disablepixeljitter", _, Some([b])) => self.desc.pixel_jitter = !*b,
                ("seed" | "disablepixeljitter", ..) => {
                    return Err(err(&p.loc, format!("Option \"{}\": expected an integer >= 0 (seed) or a bool (disablepixeljitter)", p.name)))
                }
                _ => self.warn(loc, format!("Option \"{}\" is ignored (seed and disablepixeljitter are read)", p.name)),
            },
            Directive::ColorSpace(n) => {
                if n != "srgb" {
                    self.warn(
                        loc,
                        format!("ColorSpace \"{n}\": rgb values are read as sRGB"),
                    );
                }
            }
            Directive::Camera(ty, p) => {
                if ty != "perspective" && ty != "orthographic" {
                    return Err(err(
                        loc,
                        format!("camera \"{ty}\" is not supported (perspective, orthographic)"),
                    ));
                }
                self.named_coords
                    .insert("camera".into(), self.st.ctm.inverse());
                self.desc.camera = Some(Camera {
                    entity: self.entity(ty, p, loc),
                    camera_from_world: self.st.ctm,
                    medium: self.st.outside.clone(),
                });
            }
            Directive::Film(ty, p) => self.desc.film = Some(self.entity(ty, p, loc)),
            Directive::Sampler(ty, p) => self.desc.sampler = Some(self.entity(ty, p, loc)),
            Directive::Integrator(ty, p) => self.desc.integrator = Some(self.entity(ty, p, loc)),
            Directive::PixelFilter(ty, p) => self.desc.filter = Some(self.entity(ty, p, loc)),
            Directive::Accelerator(..) => {}
            Directive::WorldBegin => {
                self.st.ctm = DMat4::IDENTITY;
                self.named_coords.insert("world".into(), DMat4::IDENTITY);
            }
            Directive::LightSource(ty, p) => {
                let entity = self.entity(ty, p, loc);
                self.desc.world.push(World::Light {
                    entity,
                    ctm: self.st.ctm,
                });
            }
            Directive::AreaLightSource(ty, p) => {
                self.st.area = Some(self.desc.area_lights.len());
                let entity = self.entity(ty, p, loc);
                self.desc.area_lights.push(entity);
            }
            Directive::Material(ty, p) => {
                self.st.material = MaterialRef::Entity(self.desc.materials.len());
                let entity = self.entity(ty, p, loc);
                self.desc.materials.push(Material { name: None, entity });
            }
            Directive::MakeNamedMaterial(name, p) => {
                let ty = ParamDict::new(&p).string("type").unwrap_or("").to_string();
                if ty.is_empty() {
                    return Err(err(
                        loc,
                        format!("MakeNamedMaterial \"{name}\": missing \"string type\""),
                    ));
                }
                self.named_materials
                    .insert(name.clone(), self.desc.materials.len());
                let entity = self.entity(ty, p, loc);
                self.desc.materials.push(Material {
                    name: Some(name),
                    entity,
                });
            }
            Directive::NamedMaterial(name) => match self.named_materials.get(&name) {
                Some(&m) => self.st.material = MaterialRef::Entity(m),
                None => {
                    return Err(err(
                        loc,
                        format!("NamedMaterial \"{name}\": no such material"),
                    ))
                }
            },
            Directive::Texture(name, _ty, class, p) => {
                let entity = self.entity(class, p, loc);
                self.desc.textures.push(Texture { name, entity });
            }
            Directive::Shape(ty, p) => self.shape(ty, p, loc),
            Directive::MakeNamedMedium(name, p) => {
                // (pbrt-v4 refuses a redefinition too: the second would silently replace the first.)
                if self.desc.media.iter().any(|m| m.name == name) {
                    return Err(err(loc, format!("MakeNamedMedium \"{name}\": a medium of that name is already defined; give each medium its own name")));
                }
                let ty = ParamDict::new(&p).string("type").unwrap_or("").to_string();
                let entity = self.entity(ty, p, loc);
                self.desc.media.push(Medium {
                    name,
                    entity,
                    ctm: self.st.ctm,
                });
            }
            Directive::MediumInterface(i, o) => {
                for n in [&i, &o] {
                    if !n.is_empty() && !self.desc.media.iter().any(|m| &m.name == n) {
                        return Err(err(
                            loc,
                            format!("MediumInterface: no medium named \"{n}\""),
                        ));
                    }
                }
                self.st.inside = i;
                self.st.outside = o;
            }
        }
        Ok(())
    }

    /// `ObjectBegin`, `ObjectEnd` and `ObjectInstance`: objects defined once and instanced.
    fn object(&mut self, d: Directive, loc: &Loc) -> Result<(), Error> {
        match d {
            Directive::ObjectBegin(n) => {
                if let Some(open) = &self.open_object {
                    return Err(err(loc, format!("ObjectBegin \"{n}\" inside object \"{}\": objects do not nest (as pbrt-v4)", open.name)));
                }
                self.stack.push((self.st.clone(), loc.clone()));
                self.open_object = Some(Object {
                    name: n,
                    shapes: Vec::new(),
                });
            }
            Directive::ObjectEnd => {
                let Some(object) = self.open_object.take() else {
                    return Err(err(loc, "ObjectEnd without ObjectBegin"));
                };
                self.objects
                    .insert(object.name.clone(), self.desc.objects.len());
                self.desc.objects.push(object);
                if let Some((s, _)) = self.stack.pop() {
                    self.st = s;
                }
            }
            Directive::ObjectInstance(n) => {
                if let Some(open) = &self.open_object {
                    return Err(err(loc, format!("ObjectInstance \"{n}\" inside object \"{}\": an instance cannot be part of an object's definition (as pbrt-v4)", open.name)));
                }
                let object = *self
                    .objects
                    .get(&n)
                    .ok_or_else(|| err(loc, format!("ObjectInstance \"{n}\": no such object")))?;
                self.desc.world.push(World::Instance {
                    object,
                    name: n,
                    ctm: self.st.ctm,
                    loc: loc.clone(),
                    order: self.order,
                });
            }
            _ => {}
        }
        Ok(())
    }

    /// A `Shape`, with the graphics state's transform, material, area light and media, in the world or in the
    /// object being defined.
    fn shape(&mut self, ty: String, p: Vec<Param>, loc: &Loc) {
        let mut area = self.st.area;
        if let (Some(_), Some(object)) = (area, &self.open_object) {
            let m = format!("{ty} in object \"{}\": area lights are not supported with object instancing (as pbrt-v4): the shape is kept, its emission left out", object.name);
            self.warn(loc, m);
            area = None;
        }
        let shape = Shape {
            entity: self.entity(ty, p, loc),
            ctm: self.st.ctm,
            reverse: self.st.reverse,
            material: self.st.material,
            area,
            inside: self.st.inside.clone(),
            outside: self.st.outside.clone(),
        };
        match &mut self.open_object {
            Some(object) => object.shapes.push(shape),
            None => self.desc.world.push(World::Shape(shape)),
        }
    }
}

/// pbrt-v4's LookAt: the camera-from-world matrix (pbrt's left-handed camera space).
fn look_at(v: &[f64; 9]) -> DMat4 {
    let (pos, look, up) = (
        DVec3::new(v[0], v[1], v[2]),
        DVec3::new(v[3], v[4], v[5]),
        DVec3::new(v[6], v[7], v[8]),
    );
    let dir = (look - pos).normalize_or_zero();
    let right = up.normalize_or_zero().cross(dir).normalize_or_zero();
    let new_up = dir.cross(right);
    let world_from_camera = DMat4::from_cols(
        right.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        pos.extend(1.0),
    );
    world_from_camera.inverse()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn describe(text: &str) -> Result<Description, Error> {
        let mut reader = Reader::default();
        let parsed = firemedium_pbrt_parser::parse_str(
            "s.pbrt",
            text,
            std::path::Path::new("/nonexistent"),
            &mut reader,
        );
        reader.finish(parsed)
    }

    /// Reading opens nothing and builds nothing: a missing mesh and a missing grid are entities with their places,
    /// each shape carries the state it was given in, and names resolve as pbrt-v4 resolves them.
    #[test]
    fn a_scene_is_read_into_entities_before_anything_is_built() {
        let d = describe(
            "LookAt 0 -3 1  0 0 0  0 0 1\nCamera \"perspective\"\nWorldBegin\n\
             MakeNamedMedium \"fire\" \"string type\" \"fire\" \"string filename\" \"missing.vdb\"\n\
             MakeNamedMaterial \"m\" \"string type\" \"diffuse\"\n\
             AttributeBegin\n  NamedMaterial \"m\"\n  AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n  MediumInterface \"fire\" \"\"\n  Translate 1 2 3\n  Shape \"plymesh\" \"string filename\" \"missing.ply\"\nAttributeEnd\n\
             MakeNamedMaterial \"m\" \"string type\" \"conductor\"\n\
             ObjectBegin \"o\"\n  Shape \"sphere\"\nObjectEnd\n\
             LightSource \"point\"\n  ObjectInstance \"o\"\n",
        )
        .unwrap();
        assert_eq!(d.media.len(), 1);
        assert_eq!(
            (d.media[0].entity.ty.as_str(), d.media[0].entity.loc.line),
            ("fire", 4)
        );
        assert_eq!(d.materials.len(), 2);
        assert_eq!(d.area_lights.len(), 1);
        assert_eq!(d.world.len(), 3, "{:?}", d.world);
        let World::Shape(s) = &d.world[0] else {
            panic!("{:?}", d.world[0])
        };
        assert_eq!(
            (s.entity.ty.as_str(), s.entity.loc.line, s.entity.loc.col),
            ("plymesh", 11, 3)
        );
        // The material named when the shape was read (the second "m" came after it), its light, its media.
        assert_eq!(s.material, MaterialRef::Entity(0));
        assert_eq!(s.area, Some(0));
        assert_eq!((s.inside.as_str(), s.outside.as_str()), ("fire", ""));
        assert_eq!(s.ctm.w_axis.truncate(), DVec3::new(1.0, 2.0, 3.0));
        assert!(matches!(&d.world[1], World::Light { entity, .. } if entity.ty == "point"));
        assert!(matches!(&d.world[2], World::Instance { object: 0, loc, .. } if loc.line == 18));
        assert_eq!(d.objects[0].shapes.len(), 1);
        // The camera, and each entity's place in the order.
        let camera = d.camera.as_ref().unwrap();
        assert_eq!(camera.entity.loc.line, 2);
        assert!(d.media[0].entity.order < s.entity.order);
    }

    /// A name used before it is defined is refused where it is used, as pbrt-v4 does; so is a block left open.
    #[test]
    fn names_are_resolved_where_they_are_read() {
        for (text, line, what) in [
            ("WorldBegin\nNamedMaterial \"x\"\n", 2, "no such material"),
            ("WorldBegin\nMediumInterface \"fog\" \"\"\n", 2, "no medium named \"fog\""),
            ("WorldBegin\nObjectInstance \"o\"\nObjectBegin \"o\"\nObjectEnd\n", 2, "no such object"),
            ("WorldBegin\nAttributeBegin\nShape \"sphere\"\n", 2, "without its End"),
            (
                "WorldBegin\nMakeNamedMedium \"a\" \"string type\" \"homogeneous\"\nMakeNamedMedium \"a\" \"string type\" \"homogeneous\"\n",
                3,
                "already defined",
            ),
        ] {
            let e = describe(text).unwrap_err();
            assert_eq!(e.loc().map(|l| l.line), Some(line), "{text}: {e}");
            assert!(e.to_string().contains(what), "{text}: {e}");
        }
    }
}
