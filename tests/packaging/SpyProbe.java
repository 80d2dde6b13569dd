// A Java agent the rdtf-spy test loads into lcm-spy's JVM (JDK_JAVA_OPTIONS=-javaagent:...): it
// reads lcm-spy's channel table from inside, the way a user reads the window, and prints
//   ROW <channel> <type> <messages> undecodable=<count>
// for every channel whose row changed; once every channel kind the test waits for shows a decoded
// type (an lcm-gen class name, "..._t"; lcm-spy leaves it empty for an unknown fingerprint), it double-clicks the first of them (opening lcm-spy's message view, which needs jchart2d)
// and prints "VIEW <class of the opened panel>" when the view shows, or "VIEW-ERROR <exception>".
// Arguments (agent options): comma-separated channel kinds, e.g. "MANIFEST,DESCRIPTION".
import java.awt.Component;
import java.awt.Container;
import java.awt.Frame;
import java.awt.Rectangle;
import java.awt.Window;
import java.awt.event.MouseEvent;
import java.lang.instrument.Instrumentation;
import java.util.HashMap;
import java.util.Map;
import javax.swing.JTable;
import javax.swing.SwingUtilities;

public class SpyProbe {
  public static void premain(String options, Instrumentation instrumentation) {
    String[] kinds = options == null || options.isEmpty() ? new String[0] : options.split(",");
    Thread thread = new Thread(() -> run(kinds), "rdtf-spy-probe");
    thread.setDaemon(true);
    thread.start();
  }

  static JTable findTable(Component component) {
    if (component instanceof JTable) return (JTable) component;
    if (component instanceof Container) {
      for (Component child : ((Container) component).getComponents()) {
        JTable table = findTable(child);
        if (table != null) return table;
      }
    }
    return null;
  }

  static boolean hasComponentNamed(Component component, String className) {
    if (component.getClass().getName().equals(className) && component.isShowing()) return true;
    if (component instanceof Container) {
      for (Component child : ((Container) component).getComponents()) {
        if (hasComponentNamed(child, className)) return true;
      }
    }
    return false;
  }

  static String kind(String channel) { return channel.substring(channel.lastIndexOf('/') + 1); }

  static void run(String[] kinds) {
    Map<String, String> printed = new HashMap<>();
    boolean clicked = false;
    try {
      while (true) {
        final Object[][] rows = new Object[1][];
        final int[] clickRow = {-1};
        SwingUtilities.invokeAndWait(() -> {
          for (Frame frame : Frame.getFrames()) {
            JTable table = findTable(frame);
            if (table == null) continue;
            Object[] out = new Object[table.getRowCount()];
            for (int r = 0; r < table.getRowCount(); ++r) {
              out[r] = new String[] {String.valueOf(table.getValueAt(r, 0)), String.valueOf(table.getValueAt(r, 1)),
                                     String.valueOf(table.getValueAt(r, 2)),
                                     String.valueOf(table.getValueAt(r, table.getColumnCount() - 1))};
            }
            rows[0] = out;
          }
        });
        if (rows[0] != null) {
          Map<String, Integer> decodedRowOfKind = new HashMap<>();
          for (int r = 0; r < rows[0].length; ++r) {
            String[] row = (String[]) rows[0][r];
            String line = row[1] + " " + row[2] + " undecodable=" + row[3];
            if (!line.equals(printed.get(row[0]))) {
              printed.put(row[0], line);
              System.out.println("ROW " + row[0] + " " + line);
            }
            if (row[1].endsWith("_t")) decodedRowOfKind.putIfAbsent(kind(row[0]), r);
          }
          boolean all = kinds.length > 0;
          for (String k : kinds) all &= decodedRowOfKind.containsKey(k);
          if (all && !clicked) {
            clicked = true;
            openView(decodedRowOfKind.get(kinds[0]));
          }
        }
        if (clicked) {
          final boolean[] shown = {false};
          SwingUtilities.invokeAndWait(() -> {
            for (Window window : Window.getWindows()) {
              if (!(window instanceof Frame) || !hasComponentNamed(window, "lcm.spy.ObjectPanel")) continue;
              shown[0] = true;
              window.setLocation(810, 0);  // beside the channel table (Xvfb has no window manager)
            }
          });
          if (shown[0]) {
            System.out.println("VIEW lcm.spy.ObjectPanel");
            System.out.flush();
            return;
          }
        }
        System.out.flush();
        Thread.sleep(100);  // lcm-spy has no hook to wait on; its table refreshes on Swing's thread
      }
    } catch (Throwable error) {
      System.out.println("VIEW-ERROR " + error);
      System.out.flush();
    }
  }

  // lcm-spy opens a channel's message view on a double click in its table.
  static void openView(int row) throws Exception {
    SwingUtilities.invokeAndWait(() -> {
      for (Frame frame : Frame.getFrames()) {
        JTable table = findTable(frame);
        if (table == null) continue;
        Rectangle cell = table.getCellRect(row, 0, true);
        int x = cell.x + cell.width / 2;
        int y = cell.y + cell.height / 2;
        long now = System.currentTimeMillis();
        table.dispatchEvent(new MouseEvent(table, MouseEvent.MOUSE_PRESSED, now, 0, x, y, 2, false, MouseEvent.BUTTON1));
        table.dispatchEvent(new MouseEvent(table, MouseEvent.MOUSE_RELEASED, now, 0, x, y, 2, false, MouseEvent.BUTTON1));
        table.dispatchEvent(new MouseEvent(table, MouseEvent.MOUSE_CLICKED, now, 0, x, y, 2, false, MouseEvent.BUTTON1));
      }
    });
  }
}
