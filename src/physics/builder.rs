//! Builder methods for definitions ([`super::BodyDef`], [`super::PartDef`]): each takes the
//! definition, sets one field and hands it back.

/// `fn name(mut self, arg: Ty) -> Self { self.field = value; self }` for each line.
macro_rules! builder_setters {
    ($($(#[$doc:meta])* $name:ident($arg:ident: $ty:ty) => $field:ident = $value:expr;)*) => {
        $(
            $(#[$doc])*
            pub fn $name(mut self, $arg: $ty) -> Self {
                self.$field = $value;
                self
            }
        )*
    };
}

pub(crate) use builder_setters;
