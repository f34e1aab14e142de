// The independent XML parser the RSI scanner is held against: libxml2 (Debian's libxml2-dev, used in
// the tests only). Reads a document into a plain description (well-formed or not, the root's name and
// attributes, its direct children with their attributes and text), so a test can compare what deflex's
// scanner made of the same bytes with what a full XML parser makes of them.
#pragma once

#include <libxml/parser.h>
#include <libxml/tree.h>

#include <map>
#include <string>
#include <vector>

namespace deflex::test {

struct XmlElementView {
  std::string name;
  std::map<std::string, std::string> attributes;
  std::string text;  ///< all character data below the element (xmlNodeGetContent)
};

struct XmlDocumentView {
  bool well_formed = false;
  XmlElementView root;
  std::vector<XmlElementView> children;  ///< the root's child elements, in order
};

inline XmlElementView view_of(xmlNodePtr node) {
  XmlElementView v;
  v.name = reinterpret_cast<const char*>(node->name);
  for (xmlAttrPtr a = node->properties; a != nullptr; a = a->next) {
    xmlChar* value = xmlNodeListGetString(node->doc, a->children, 1);
    v.attributes[reinterpret_cast<const char*>(a->name)] = value != nullptr ? reinterpret_cast<const char*>(value) : "";
    xmlFree(value);
  }
  xmlChar* text = xmlNodeGetContent(node);
  v.text = text != nullptr ? reinterpret_cast<const char*>(text) : "";
  xmlFree(text);
  return v;
}

/// Parses with libxml2, no network, no error output; well_formed false when libxml2 refuses it.
inline XmlDocumentView libxml2_read(const std::string& bytes) {
  XmlDocumentView out;
  xmlParserCtxtPtr context = xmlNewParserCtxt();
  xmlDocPtr doc = xmlCtxtReadMemory(context, bytes.data(), static_cast<int>(bytes.size()), "document.xml", nullptr,
                                    XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
  out.well_formed = doc != nullptr && context->wellFormed != 0;
  xmlFreeParserCtxt(context);
  if (doc == nullptr) return out;
  if (xmlNodePtr root = xmlDocGetRootElement(doc); root != nullptr) {
    out.root = view_of(root);
    for (xmlNodePtr c = root->children; c != nullptr; c = c->next) {
      if (c->type == XML_ELEMENT_NODE) out.children.push_back(view_of(c));
    }
  } else {
    out.well_formed = false;
  }
  xmlFreeDoc(doc);
  return out;
}

/// Every element named `name` anywhere in a well-formed document, in document order (empty when the
/// document is not well-formed).
inline std::vector<XmlElementView> libxml2_elements(const std::string& bytes, const std::string& name) {
  std::vector<XmlElementView> out;
  xmlParserCtxtPtr context = xmlNewParserCtxt();
  xmlDocPtr doc = xmlCtxtReadMemory(context, bytes.data(), static_cast<int>(bytes.size()), "document.xml", nullptr,
                                    XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
  const bool well_formed = doc != nullptr && context->wellFormed != 0;
  xmlFreeParserCtxt(context);
  if (doc == nullptr) return out;
  if (well_formed) {
    std::vector<xmlNodePtr> stack{xmlDocGetRootElement(doc)};
    while (!stack.empty()) {
      xmlNodePtr node = stack.back();
      stack.pop_back();
      if (node == nullptr || node->type != XML_ELEMENT_NODE) continue;
      if (name == reinterpret_cast<const char*>(node->name)) out.push_back(view_of(node));
      std::vector<xmlNodePtr> children;
      for (xmlNodePtr c = node->children; c != nullptr; c = c->next) children.push_back(c);
      stack.insert(stack.end(), children.rbegin(), children.rend());
    }
  }
  xmlFreeDoc(doc);
  return out;
}

}  // namespace deflex::test
