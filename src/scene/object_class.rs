//! The one vocabulary of what a scene object is — a floor, a wall, a seat, a table, a bed,
//! storage, an appliance … — and the one table of words by which a name or a scan's label
//! says so. Seats (`seats`: which objects may be sat on), drawn materials
//! (`render::materials`: which patterns an object gets) and generated scenes (the names
//! they give their objects) all read an object's class here. A name is only a hint where
//! geometry decides: a seat needs no name, and a name that says "table" refuses one.

use serde::{Deserialize, Serialize};

/// What a scene object is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectClass {
    Floor,
    Wall,
    Ceiling,
    /// A rug or carpet lying on the floor.
    Carpet,
    Door,
    /// Windows, mirrors, glass panes: see-through or reflecting.
    Window,
    /// Hard seats: chairs, stools, benches.
    Seat,
    /// Upholstered seats: sofas, couches, armchairs, ottomans.
    Sofa,
    Bed,
    /// Tables, desks, counters.
    Table,
    /// Shelves, cabinets, cupboards, drawers, wardrobes, nightstands.
    Storage,
    /// Kitchen and bathroom fixtures and machines: fridges, ovens, sinks, toilets.
    Appliance,
    /// Televisions, monitors, screens.
    Screen,
    /// Lamps and light fittings.
    Light,
    /// Cushions, pillows, curtains.
    Textile,
    /// Plants, trees, flowers.
    Plant,
    /// Small things that keep their own look: books, balls, cups, bins.
    SmallObject,
    /// Pictures, paintings and posters hung on walls.
    Picture,
}

/// Words that name a class, in the order they are tried (the first found wins): a word is
/// found at the start of a word of the name (after a non-letter, or where camel case starts
/// one), so `floor_living`, `IKEA_bed_FJELLSE`, `HouseWallB_01` and `IKEAShelf_mesh` say
/// `floor`, `bed`, `wall` and `shelf`, and `sofabed` says `sofa`.
const CLASS_WORDS: &[(&str, ObjectClass)] = &[
    ("plant", ObjectClass::Plant),
    ("picture", ObjectClass::Picture),
    ("painting", ObjectClass::Picture),
    ("poster", ObjectClass::Picture),
    ("tree", ObjectClass::Plant),
    ("flower", ObjectClass::Plant),
    ("leaf", ObjectClass::Plant),
    ("leaves", ObjectClass::Plant),
    ("bookcase", ObjectClass::Storage),
    ("book", ObjectClass::SmallObject),
    ("ball", ObjectClass::SmallObject),
    ("trash", ObjectClass::SmallObject),
    ("bin", ObjectClass::SmallObject),
    ("mailbox", ObjectClass::SmallObject),
    ("window", ObjectClass::Window),
    ("glass", ObjectClass::Window),
    ("mirror", ObjectClass::Window),
    ("tv", ObjectClass::Screen),
    ("television", ObjectClass::Screen),
    ("monitor", ObjectClass::Screen),
    ("screen", ObjectClass::Screen),
    ("carpet", ObjectClass::Carpet),
    ("rug", ObjectClass::Carpet),
    ("ceiling", ObjectClass::Ceiling),
    ("floor", ObjectClass::Floor),
    ("ground", ObjectClass::Floor),
    ("step", ObjectClass::Floor),
    ("stair", ObjectClass::Floor),
    ("wall", ObjectClass::Wall),
    ("sofa", ObjectClass::Sofa),
    ("couch", ObjectClass::Sofa),
    ("settee", ObjectClass::Sofa),
    ("loveseat", ObjectClass::Sofa),
    ("futon", ObjectClass::Sofa),
    ("armchair", ObjectClass::Sofa),
    ("ottoman", ObjectClass::Sofa),
    ("pouf", ObjectClass::Sofa),
    ("bed", ObjectClass::Bed),
    ("cushion", ObjectClass::Textile),
    ("pillow", ObjectClass::Textile),
    ("curtain", ObjectClass::Textile),
    ("lamp", ObjectClass::Light),
    ("chandelier", ObjectClass::Light),
    ("light", ObjectClass::Light),
    // A kitchen's or workshop's "bench" is a worktop, not a seat.
    ("cookingbench", ObjectClass::Table),
    ("workbench", ObjectClass::Table),
    ("chair", ObjectClass::Seat),
    ("stool", ObjectClass::Seat),
    ("bench", ObjectClass::Seat),
    ("seat", ObjectClass::Seat),
    ("table", ObjectClass::Table),
    ("desk", ObjectClass::Table),
    ("counter", ObjectClass::Table),
    ("shelf", ObjectClass::Storage),
    ("shelves", ObjectClass::Storage),
    ("cupboard", ObjectClass::Storage),
    ("cabinet", ObjectClass::Storage),
    ("chest", ObjectClass::Storage),
    ("drawer", ObjectClass::Storage),
    ("dresser", ObjectClass::Storage),
    ("wardrobe", ObjectClass::Storage),
    ("console", ObjectClass::Storage),
    ("nightstand", ObjectClass::Storage),
    ("rack", ObjectClass::Storage),
    ("door", ObjectClass::Door),
    ("sink", ObjectClass::Appliance),
    ("stove", ObjectClass::Appliance),
    ("oven", ObjectClass::Appliance),
    ("fridge", ObjectClass::Appliance),
    ("refrigerator", ObjectClass::Appliance),
    ("toilet", ObjectClass::Appliance),
    ("washbasin", ObjectClass::Appliance),
    ("shower", ObjectClass::Appliance),
    ("radiator", ObjectClass::Appliance),
    // A generated dwelling's small things (`scene::dwelling`).
    ("thing", ObjectClass::SmallObject),
];

impl ObjectClass {
    /// The class the first listed word found at a word's start in `text` names, if any.
    pub(crate) fn by_words(text: &str) -> Option<ObjectClass> {
        let chars: Vec<(usize, char)> = text.char_indices().collect();
        let starts: Vec<usize> = (0..chars.len())
            .filter(|&k| {
                let c = chars[k].1;
                let prev = k.checked_sub(1).map(|j| chars[j].1);
                let next = chars.get(k + 1).map(|&(_, n)| n);
                c.is_alphabetic()
                    && match prev {
                        None => true,
                        Some(p) if !p.is_alphabetic() => true,
                        Some(p) => {
                            c.is_uppercase()
                                && (p.is_lowercase() || next.is_some_and(char::is_lowercase))
                        }
                    }
            })
            .map(|k| chars[k].0)
            .collect();
        let lower: Vec<String> = starts.iter().map(|&i| text[i..].to_lowercase()).collect();
        CLASS_WORDS
            .iter()
            .find(|(word, _)| lower.iter().any(|rest| rest.starts_with(word)))
            .map(|&(_, class)| class)
    }

    /// What an object's name says it is, else what its label says (a scan's class label).
    pub(crate) fn named(name: &str, label: Option<&str>) -> Option<ObjectClass> {
        Self::by_words(name).or_else(|| label.and_then(Self::by_words))
    }

    /// Something people sit on: a seat, a sofa or a bed.
    pub(crate) fn is_seat(self) -> bool {
        matches!(
            self,
            ObjectClass::Seat | ObjectClass::Sofa | ObjectClass::Bed
        )
    }

    /// Every class, in the order of the enum.
    #[cfg(test)]
    const ALL: [ObjectClass; 18] = [
        ObjectClass::Floor,
        ObjectClass::Wall,
        ObjectClass::Ceiling,
        ObjectClass::Carpet,
        ObjectClass::Door,
        ObjectClass::Window,
        ObjectClass::Seat,
        ObjectClass::Sofa,
        ObjectClass::Bed,
        ObjectClass::Table,
        ObjectClass::Storage,
        ObjectClass::Appliance,
        ObjectClass::Screen,
        ObjectClass::Light,
        ObjectClass::Textile,
        ObjectClass::Plant,
        ObjectClass::SmallObject,
        ObjectClass::Picture,
    ];
}

#[cfg(test)]
mod tests {
    use super::ObjectClass as C;

    #[test]
    fn names_say_their_class_at_a_words_start() {
        let cases = [
            ("IKEA_armchair_EKTORP.001", Some(C::Sofa)),
            ("IKEA_bed_FJELLSE", Some(C::Bed)),
            ("ChairD_01_003", Some(C::Seat)),
            ("SofaC_01_001", Some(C::Sofa)),
            ("HouseWallB_01", Some(C::Wall)),
            ("IKEAShelf_mesh", Some(C::Storage)),
            ("floor_living", Some(C::Floor)),
            ("sofabed", Some(C::Sofa)),
            ("bench_park", Some(C::Seat)),
            ("CookingBench_01_001", Some(C::Table)),
            ("DiningTable", Some(C::Table)),
            ("Refrigerator_01", Some(C::Appliance)),
            ("FitnessEquipment_01_001", None),
            // Inside a word is no word: "tablet" is a table's start, "cabinet" holds no "bin".
            ("cabinet", Some(C::Storage)),
            ("Stuhl", None),
            ("Bookcase_2", Some(C::Storage)),
            ("book_red", Some(C::SmallObject)),
        ];
        for (name, class) in cases {
            assert_eq!(C::by_words(name), class, "{name}");
        }
        assert_eq!(C::named("object_17", Some("chair")), Some(C::Seat));
        assert_eq!(C::named("Table_2", Some("chair")), Some(C::Table));
        assert!(C::Bed.is_seat() && C::Sofa.is_seat() && !C::Table.is_seat());
    }

    #[test]
    fn every_class_is_listed_and_named_by_some_word() {
        for c in C::ALL {
            assert!(
                super::CLASS_WORDS.iter().any(|&(_, k)| k == c),
                "{c:?} has no word"
            );
        }
    }
}
