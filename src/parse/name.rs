//! Interned names: every `Name` with the same text shares one allocation, so
//! maps keyed by names hash and compare a pointer, not the text.

use std::cell::RefCell;
use std::collections::HashSet;
use std::fmt;
use std::hash::{Hash, Hasher};
use std::ops::Deref;
use std::rc::Rc;

thread_local! {
    /// Every name made on this thread (names never cross threads: `Rc`).
    static NAMES: RefCell<HashSet<Rc<str>>> = RefCell::new(HashSet::new());
    /// Names kept after the last [`Name::forget_unused`].
    static KEPT: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// A parameter name or label key, interned per thread.
#[derive(Clone)]
pub struct Name(Rc<str>);

impl Name {
    /// The name with this text (the one already made, if any).
    pub fn new(text: &str) -> Name {
        NAMES.with(|set| {
            let mut set = set.borrow_mut();
            if let Some(rc) = set.get(text) {
                return Name(rc.clone());
            }
            let rc: Rc<str> = Rc::from(text);
            set.insert(rc.clone());
            Name(rc)
        })
    }

    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// Drops the names nothing but the table holds (labels read while
    /// indexing a file and not kept, for example): a file of a million
    /// labels does not keep a million names it no longer uses. Such a name
    /// made again is a new one, equal to every live one with its text, since
    /// no live one has it. Only when the table has at least doubled since
    /// the last time, so that the work stays linear in the names made.
    pub fn forget_unused() {
        NAMES.with(|set| {
            let mut set = set.borrow_mut();
            if set.len() < 2 * KEPT.get() + 4096 {
                return;
            }
            set.retain(|rc| Rc::strong_count(rc) > 1);
            set.shrink_to_fit();
            KEPT.set(set.len());
        })
    }
}

impl PartialEq for Name {
    #[inline]
    fn eq(&self, other: &Name) -> bool {
        Rc::ptr_eq(&self.0, &other.0)
    }
}

impl Eq for Name {}

impl Hash for Name {
    #[inline]
    fn hash<H: Hasher>(&self, state: &mut H) {
        state.write_usize(Rc::as_ptr(&self.0) as *const u8 as usize);
    }
}

impl Deref for Name {
    type Target = str;
    #[inline]
    fn deref(&self) -> &str {
        &self.0
    }
}

impl fmt::Debug for Name {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(&*self.0, f)
    }
}

impl fmt::Display for Name {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::Name;
    use std::collections::HashMap;

    #[test]
    fn equal_texts_are_one_name_and_find_each_other() {
        let a = Name::new("depth");
        let b = Name::new(&(String::from("dep") + "th"));
        assert_eq!(a, b);
        assert_ne!(a, Name::new("depth2"));
        let mut m = HashMap::new();
        m.insert(a, 1.5);
        assert_eq!(m.get(&b), Some(&1.5));
        assert_eq!(m.get(&Name::new("Depth")), None);
    }

    #[test]
    fn forgetting_unused_names_keeps_the_live_ones() {
        let live: Vec<Name> = (0..3000).map(|k| Name::new(&format!("live{k}"))).collect();
        for k in 0..20_000 {
            Name::new(&format!("gone{k}"));
        }
        let count = || super::NAMES.with(|s| s.borrow().len());
        let before = count();
        Name::forget_unused();
        assert!(count() <= before - 20_000, "{} of {before}", count());
        for (k, n) in live.iter().enumerate() {
            assert_eq!(*n, Name::new(&format!("live{k}")));
        }
        assert_eq!(Name::new("gone7").as_str(), "gone7");
        assert_eq!(Name::new("gone7"), Name::new("gone7"));
    }
}
