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
}
